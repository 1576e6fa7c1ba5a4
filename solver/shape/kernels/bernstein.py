"""Quadratic Bernstein functions (review 3.5, eqs. 3.22-3.25): TLMPM only.

A quadratic element has three nodes per axis, on its two ends and at its centre
(review Fig. 22). Here the background grid's nodes are those nodes: an element
spans two grid cells, so the grid needs an even number of cells per axis (scene
validation) and `cell_size` is half the element size. In an element with local
coordinate t in [0, 1] the weights are B_{0,2} = (1 - t)^2 on the lower end node,
B_{1,2} = 2 t (1 - t) on the centre node and B_{2,2} = t^2 on the upper end node:
eqs. 3.24 (end node, (1 - |r|)^2) and 3.25 (centre node, 1/2 - 2 r^2) with r in
element sizes. They are non-negative, a partition of unity and reproduce linear
fields (the nodes are the control points of the straight line), but they do not
interpolate (the centre node's weight peaks at 1/2) and their gradient jumps
across element ends (C0). That jump is the cell-crossing noise of review 3.2 as
soon as particles move across elements, which is why the review recommends them
only for TLMPM, where the weights are evaluated once in the reference
configuration.
"""
from __future__ import annotations

from solver.jit import njit

from solver.shape.kernels import tensor




@njit(cache=True)
def axis(s, a, p, cells, inv_h, data, w1, g1):
    """The three nodes of the two-cell element holding s (in cells) along axis a."""
    if not (s >= 0.0 and s <= 2 * (cells // 2)):   # also catches NaN
        return -1
    e = min(int(0.5 * s), cells // 2 - 1)           # the element: cells 2e, 2e + 1
    t = 0.5 * s - e
    w1[a, 0] = (1.0 - t) ** 2
    w1[a, 1] = 2.0 * t * (1.0 - t)
    w1[a, 2] = t * t
    # dt/dx = 1 / (2 h)
    g1[a, 0] = -(1.0 - t) * inv_h
    g1[a, 1] = (1.0 - 2.0 * t) * inv_h
    g1[a, 2] = t * inv_h
    return 2 * e


# the 1D function and the declared support (solver/shape/bernstein.py), as the tensor kernel takes them
NODES = tensor.nodes_of("bernstein")


def weights(spec, x, lower, inv_h, cells, strides, idx, w, dw, blocks):
    kernel = tensor.kernels("bernstein").weights   # (generated once: tensor.py)
    return kernel(NODES, spec, x, tensor.NO_DATA, lower, inv_h, cells, strides, idx, w, dw, blocks)
