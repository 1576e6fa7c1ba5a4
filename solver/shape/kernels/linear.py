"""Linear hat functions (review eq. 3.1-3.3, Karamelo eq. 2.1-2.4).

In 1D N_I(x) = 1 - |x - x_I| / h on the two nodes of the cell holding x; in 2D
and 3D the tensor product over axes. Their gradient jumps at cell faces, which
is the cell-crossing noise of standard MPM (review 3.2).
"""
from __future__ import annotations

import numpy as np
from solver.jit import njit, prange

from solver.threads import block_bounds, first_of


# The 1D functions: the formula both backends evaluate (this module's kernel, and the fused
# kernels through solver/fused.py `_axis`), inlined into both (quadratic_bspline.py says why).
@njit(inline="always")
def inside(s, cells):
    """Whether a position s (in cells from the grid's lower end) has its nodes on an axis of
    `cells` cells (False for NaN)."""
    return s >= 0.0 and s <= cells


@njit(inline="always")
def first_node(s, cells):
    """The first of the two nodes of a position s inside the grid."""
    return min(int(s), cells - 1)


@njit(inline="always")
def weights_1d(f):
    """The weights on the nodes at -f and 1 - f cells (f in [0, 1])."""
    return 1.0 - f, f


@njit(inline="always")
def gradients_1d(inv_h):
    """d(weights_1d)/dx on the same nodes."""
    return -inv_h, inv_h


# Hat functions keep a kernel of their own instead of the shared one of tensor.py: their
# per-axis work is so small that calling a separate axis function made the weights 1.45x
# slower (3D, 21 -> 31 ns a particle); every other shape function gained from the shared one.
@njit(parallel=True, cache=True)
def weights(spec, x, lower, inv_h, cells, strides, idx, w, dw, blocks):
    dims, nodes = spec
    bounds = block_bounds(x.shape[0], blocks)
    bad = np.empty(blocks, dtype=np.int64)
    for t in prange(blocks):
        bad[t] = _block(dims, nodes, bounds[t], bounds[t + 1], x, lower, inv_h, cells, strides, idx, w, dw)
    return first_of(bad)


@njit(cache=True)
def _block(dims, nodes, start, stop, x, lower, inv_h, cells, strides, idx, w, dw):
    """The particles start..stop-1 (a parallel kernel's block, solver/kernels.py)."""
    dim, nk = len(dims), len(nodes)
    base = np.empty(dim, dtype=np.int64)
    w1 = np.empty((dim, 2))   # 1D weights of the two nodes, per axis
    g1 = np.empty((dim, 2))   # their derivatives
    for p in range(np.uint64(start), np.uint64(stop)):   # unsigned: no wrap-around test (docs/internals.md)
        for a in range(dim):
            s = (x[p, a] - lower[a]) * inv_h[a]
            if not inside(s, cells[a]):
                return np.int64(p)
            i = first_node(s, cells[a])
            base[a] = i
            w1[a, 0], w1[a, 1] = weights_1d(s - i)
            g1[a, 0], g1[a, 1] = gradients_1d(inv_h[a])
        for k in range(nk):
            node = 0
            wk = 1.0
            for a in range(dim):
                bit = (k >> a) & 1
                node += (base[a] + bit) * strides[a]
                wk *= w1[a, bit]
            idx[p, k] = node
            w[p, k] = wk
            for d in range(dim):
                g = 1.0
                for a in range(dim):
                    bit = (k >> a) & 1
                    g *= g1[a, bit] if a == d else w1[a, bit]
                dw[p, k, d] = g
    return -1
