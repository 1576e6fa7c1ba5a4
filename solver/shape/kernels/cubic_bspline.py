"""Cubic B-splines with the boundary-modified functions of review 3.4 (Steffen et
al. 2008; review eqs. 3.18-3.21).

A grid of n cells keeps its n + 1 nodes (review Remark 26). With r = (x - x_I)/h
the 1D function of node I depends on where the node sits:
type 1 on a grid end, type 2 one cell inside the lower end, type 4 one cell
inside the upper end (type 2 mirrored), type 3 everywhere else (the standard
cubic B-spline). Only type 1 is non-zero on a grid end, so the functions
interpolate there, keep the partition of unity and linear reproduction up to
the grid ends, and never need a node outside the grid. Four nodes per axis;
the grid needs at least 3 cells per axis (scene validation).
"""
from __future__ import annotations

from solver.jit import njit

from solver.shape.kernels import tensor




@njit(cache=True)
def spline(kind, mirror, r):
    """(S(r), dS/dr) of the 1D function of type `kind` (1..3), mirrored about its
    node when `mirror` is -1 (type 4 is type 2 mirrored; the upper end node is
    type 1 mirrored, which picks the inner one-sided derivative at r = 0)."""
    r = mirror * r
    a = abs(r)
    sign = 1.0 if r >= 0.0 else -1.0
    if a >= 2.0 or (kind == 2 and r < -1.0):
        return 0.0, 0.0
    if a >= 1.0 and not (kind == 2 and r < 0.0):   # the outer piece is (2 - |r|)^3 / 6 for every type
        return (2.0 - a) ** 3 / 6.0, -mirror * sign * 0.5 * (2.0 - a) ** 2
    if kind == 1:
        return 1.0 - a + a**3 / 6.0, mirror * sign * (-1.0 + 0.5 * a * a)
    if kind == 2 and r < 0.0:
        return -r**3 / 3.0 - r * r + 2.0 / 3.0, mirror * (-r * r - 2.0 * r)
    return 0.5 * a**3 - a * a + 2.0 / 3.0, mirror * sign * (1.5 * a * a - 2.0 * a)


@njit(cache=True)
def node_type(j, cells):
    """(type, mirror) of node j of an axis with `cells` cells."""
    if j == 0:
        return 1, 1.0
    if j == cells:
        return 1, -1.0
    if j == 1:
        return 2, 1.0
    if j == cells - 1:
        return 2, -1.0
    return 3, 1.0


@njit(cache=True)
def axis(s, a, p, cells, inv_h, data, w1, g1):
    """The four nodes around s (in cells) along axis a (solver/shape/tensor.py)."""
    if not (s >= 0.0 and s <= cells):   # also catches NaN
        return -1
    i = min(int(s), cells - 1)
    # nodes i-1 .. i+2, shifted inwards at the grid ends where the
    # modified functions vanish on the node that would fall outside
    b = min(max(i - 1, 0), cells - 3)
    for j in range(4):
        kind, mirror = node_type(b + j, cells)
        sj, dj = spline(kind, mirror, s - (b + j))
        w1[a, j] = sj
        g1[a, j] = dj * inv_h
    return b


# the 1D function and the declared support (solver/shape/cubic_bspline.py), as the tensor kernel takes them
NODES = tensor.nodes_of("cubic_bspline")


def weights(spec, x, lower, inv_h, cells, strides, idx, w, dw, blocks):
    kernel = tensor.kernels("cubic_bspline").weights   # (generated once: tensor.py)
    return kernel(NODES, spec, x, tensor.NO_DATA, lower, inv_h, cells, strides, idx, w, dw, blocks)
