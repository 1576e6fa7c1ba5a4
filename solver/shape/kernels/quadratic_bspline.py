"""Quadratic B-splines (the C1 standard of graphics MPM; review eq. 5.10 with the
corrected interval bounds +-3h/2, +-h/2 of VERIFICATION_CASES F2).

N(r) = 3/4 - r^2 for |r| < 1/2, (3/2 - |r|)^2 / 2 for 1/2 <= |r| < 3/2, with
r = (x - x_I) / h: three nodes per axis. No boundary-modified variant: a particle
closer than h/2 to a grid end would need a node beyond it, so it is reported as
outside the grid (keep one free cell between bodies and the grid ends).
"""
from __future__ import annotations

from solver.jit import njit

from solver.shape.kernels import tensor


_TOUCH = 1e-9   # round-off allowance at h/2 from a grid end (in cells)


@njit(cache=True)
def axis(s, a, p, cells, inv_h, data, w1, g1):
    """The three nodes of a position s (in cells) along axis a (solver/shape/tensor.py)."""
    if not (s >= 0.5 - _TOUCH and s <= cells - 0.5 + _TOUCH):   # also catches NaN
        return -1
    i = min(max(int(s - 0.5), 0), cells - 2)
    f = s - i                                     # in [1/2, 3/2]: distance to node i in cells
    w1[a, 0] = 0.5 * (1.5 - f) ** 2
    w1[a, 1] = 0.75 - (f - 1.0) ** 2
    w1[a, 2] = 0.5 * (f - 0.5) ** 2
    g1[a, 0] = -(1.5 - f) * inv_h
    g1[a, 1] = -2.0 * (f - 1.0) * inv_h
    g1[a, 2] = (f - 0.5) * inv_h
    return i


# the 1D function and the declared support (solver/shape/quadratic_bspline.py), as the tensor kernel takes them
NODES = tensor.nodes_of("quadratic_bspline")


def weights(spec, x, lower, inv_h, cells, strides, idx, w, dw, blocks):
    kernel = tensor.kernels("quadratic_bspline").weights   # (generated once: tensor.py)
    return kernel(NODES, spec, x, tensor.NO_DATA, lower, inv_h, cells, strides, idx, w, dw, blocks)
