"""The tensor product shared by the higher-order shape functions.

Each of them computes, per axis a, the first node `base[a]` of the particle's
stencil and the 1D weights w1[a, j] and derivatives g1[a, j] (already divided by
h) of the `support` nodes base[a] + j. The stencil node k has the per-axis
offsets j_a = (k // support**a) % support (axis 0 fastest, like the node order).
"""
from __future__ import annotations

from numba import njit


@njit(cache=True)
def scatter(p, support, base, w1, g1, strides, idx, w, dw):
    """Fill idx[p], w[p], dw[p] with the tensor products of the 1D weights."""
    dim = base.shape[0]
    nk = idx.shape[1]
    for k in range(nk):
        node = 0
        wk = 1.0
        rest = k
        for a in range(dim):
            j = rest % support
            rest //= support
            node += (base[a] + j) * strides[a]
            wk *= w1[a, j]
        idx[p, k] = node
        w[p, k] = wk
        for d in range(dim):
            g = 1.0
            rest = k
            for a in range(dim):
                j = rest % support
                rest //= support
                g *= g1[a, j] if a == d else w1[a, j]
            dw[p, k, d] = g
