"""Quadratic B-splines (the C1 standard of graphics MPM; review eq. 5.10 with the
corrected interval bounds +-3h/2, +-h/2 of VERIFICATION_CASES F2).

N(r) = 3/4 - r^2 for |r| < 1/2, (3/2 - |r|)^2 / 2 for 1/2 <= |r| < 3/2, with
r = (x - x_I) / h: three nodes per axis. No boundary-modified variant: a particle
closer than h/2 to a grid end would need a node beyond it, so it is reported as
outside the grid (keep one free cell between bodies and the grid ends).
"""
from __future__ import annotations

import numpy as np
from numba import njit, prange

from solver.shape.tensor import scatter
from solver.threads import block_bounds, first_of

SUPPORT = 3
APIC_D = 0.25   # APIC's D_p = sum_I w_Ip (x_I - x_p)^2 = h^2/4 per axis, wherever the particle is
_TOUCH = 1e-9   # round-off allowance at h/2 from a grid end (in cells)


@njit(parallel=True, cache=True)
def weights(spec, x, lower, inv_h, cells, strides, idx, w, dw, blocks):
    dims = spec[0]
    bounds = block_bounds(x.shape[0], blocks)
    bad = np.empty(blocks, dtype=np.int64)
    for t in prange(blocks):
        bad[t] = _block(dims, bounds[t], bounds[t + 1], x, lower, inv_h, cells, strides, idx, w, dw)
    return first_of(bad)


@njit(cache=True)
def _block(dims, start, stop, x, lower, inv_h, cells, strides, idx, w, dw):
    """The particles start..stop-1 (a parallel kernel's block, solver/kernels.py)."""
    dim = len(dims)
    base = np.empty(dim, dtype=np.int64)
    w1 = np.empty((dim, 3))
    g1 = np.empty((dim, 3))
    for p in range(start, stop):
        for a in range(dim):
            s = (x[p, a] - lower[a]) * inv_h[a]
            if not (s >= 0.5 - _TOUCH and s <= cells[a] - 0.5 + _TOUCH):   # also catches NaN
                return p
            i = min(max(int(s - 0.5), 0), cells[a] - 2)
            f = s - i                                     # in [1/2, 3/2]: distance to node i in cells
            base[a] = i
            w1[a, 0] = 0.5 * (1.5 - f) ** 2
            w1[a, 1] = 0.75 - (f - 1.0) ** 2
            w1[a, 2] = 0.5 * (f - 0.5) ** 2
            g1[a, 0] = -(1.5 - f) * inv_h[a]
            g1[a, 1] = -2.0 * (f - 1.0) * inv_h[a]
            g1[a, 2] = (f - 0.5) * inv_h[a]
        scatter(p, 3, base, w1, g1, strides, idx, w, dw)
    return -1
