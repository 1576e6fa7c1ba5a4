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


TOUCH = 1e-9   # round-off allowance at h/2 from a grid end (in cells)


# The 1D functions below are the formula both backends evaluate: this module's `axis` (the
# general backend, through tensor.py) and the fused kernels (solver/fused.py `_axis`, and the
# vectorised passes through `weights_1d`). They are inlined into their callers, which compile
# them with their own flags (neither caller contracts: `_axis` says fastmath=False), and as
# functions of their own they would add compilations to every cold process and a call to the
# general kernels' inner loop. The fused kernels, some contracted, call `weights_1d` as
# solver/fused.py's `_quadratic`: that copy is compiled once with fastmath=False.
@njit(inline="always")
def inside(s, cells):
    """Whether a position s (in cells from the grid's lower end) has its nodes on an axis of
    `cells` cells (False for NaN)."""
    return s >= 0.5 - TOUCH and s <= cells - 0.5 + TOUCH


@njit(inline="always")
def first_node(s, cells):
    """The first of the three nodes of a position s inside the grid."""
    return min(max(int(s - 0.5), 0), cells - 2)


@njit(inline="always")
def weights_1d(f):
    """The weights on the nodes at -f, 1 - f, 2 - f cells (f in [1/2, 3/2])."""
    return 0.5 * (1.5 - f) ** 2, 0.75 - (f - 1.0) ** 2, 0.5 * (f - 0.5) ** 2


@njit(inline="always")
def gradients_1d(f, inv_h):
    """d(weights_1d)/dx on the same nodes."""
    return -(1.5 - f) * inv_h, -2.0 * (f - 1.0) * inv_h, (f - 0.5) * inv_h


@njit(cache=True)
def axis(s, a, p, cells, inv_h, data, w1, g1):
    """The three nodes of a position s (in cells) along axis a (solver/shape/tensor.py)."""
    if not inside(s, cells):
        return -1
    i = first_node(s, cells)
    f = s - i                                     # in [1/2, 3/2]: distance to node i in cells
    w1[a, 0], w1[a, 1], w1[a, 2] = weights_1d(f)
    g1[a, 0], g1[a, 1], g1[a, 2] = gradients_1d(f, inv_h)
    return i


# the 1D function and the declared support (solver/shape/quadratic_bspline.py), as the tensor kernel takes them
NODES = tensor.nodes_of("quadratic_bspline")


def weights(spec, x, lower, inv_h, cells, strides, idx, w, dw, blocks):
    kernel = tensor.kernels("quadratic_bspline").weights   # (generated once: tensor.py)
    return kernel(NODES, spec, x, tensor.NO_DATA, lower, inv_h, cells, strides, idx, w, dw, blocks)
