"""Linear hat functions (review eq. 3.1-3.3, Karamelo eq. 2.1-2.4).

In 1D N_I(x) = 1 - |x - x_I| / h on the two nodes of the cell holding x; in 2D
and 3D the tensor product over axes. Their gradient jumps at cell faces, which
is the cell-crossing noise of standard MPM (review 3.2).
"""
from __future__ import annotations

from numba import njit

from solver.shape.kernels import tensor




@njit(cache=True)
def axis(s, a, p, cells, inv_h, data, w1, g1):
    """The two nodes of the cell holding s (in cells) along axis a (solver/shape/tensor.py)."""
    if not (s >= 0.0 and s <= cells):   # also catches NaN
        return -1
    i = min(int(s), cells - 1)
    f = s - i
    w1[a, 0] = 1.0 - f
    w1[a, 1] = f
    g1[a, 0] = -inv_h
    g1[a, 1] = inv_h
    return i


# the 1D function and the declared support (solver/shape/linear.py), as the tensor kernel takes them
AXIS, NODES = tensor.Typed(axis), tensor.nodes_of("linear")


def weights(spec, x, lower, inv_h, cells, strides, idx, w, dw, blocks):
    return tensor.weights(AXIS, NODES, spec, x, tensor.NO_DATA, lower, inv_h, cells, strides, idx, w, dw, blocks)
