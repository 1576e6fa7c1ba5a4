"""The tensor product shared by every shape function.

A shape function module gives its 1D function as a numba function

    axis(s, a, p, cells, inv_h, data, w1, g1) -> first node, or -1 outside the grid

of the position s along axis a in cells from the grid's lower end (cells: the
axis's cell count, inv_h: 1/h, data: the function's per-particle data, e.g.
GIMP's box sides, or an empty array). It fills w1[a, j] and g1[a, j] (the derivative,
already divided by h) for the `support` nodes first + j, and must test s itself
(catching NaN). `weights` below does the rest for every module: the particle
loop on the threads' blocks and the tensor products. The stencil node k has the
per-axis offsets j_a = (k // support**a) % support (axis 0 fastest, like the
node order).
"""
from __future__ import annotations

from importlib import import_module

import numba
import numpy as np
from numba import njit, prange

from solver.threads import block_bounds, first_of

NO_DATA = np.zeros((0, 0))   # `data` of the functions that need none
_SUPPORTS = {n: np.empty((0,) * n) for n in range(1, 6)}


def nodes_of(module: str) -> np.ndarray:
    """The support declared in solver/shape/<module>.py (its first name) as `weights` takes it:
    an empty array of that rank, a compile-time constant of the kernel."""
    support = import_module(f"solver.shape.{module}").SHAPE_FUNCTIONS[0].support
    return _SUPPORTS[support]


class Typed:
    """A numba function to pass to `weights` from Python, with its numba type made once:
    numba makes the type of a function argument anew at every call (about 4 us, a
    quarter of a small 1D step), but takes an object's `_numba_type_` as it is."""

    def __init__(self, function):
        self.function = function
        self._numba_type_ = numba.typeof(function)


@njit(parallel=True, cache=True)
def weights(axis, nodes, spec, x, data, lower, inv_h, cells, strides, idx, w, dw, blocks):
    """idx, w, dw of every particle (solver/shape/__init__.py); the first particle outside
    the grid, or -1. numba compiles one specialisation per `axis` function. `nodes`: an
    empty array whose rank is the support, a compile-time constant (a runtime support made
    the divisions of the tensor product cost 2-5x)."""
    dims = spec[0]
    if nodes.ndim ** len(dims) != idx.shape[1]:
        raise ValueError("the kernel's support does not match the stencil's (the declared support)")
    bounds = block_bounds(x.shape[0], blocks)
    bad = np.empty(blocks, dtype=np.int64)
    for t in prange(blocks):
        bad[t] = _block(axis, nodes, dims, bounds[t], bounds[t + 1], x, data, lower, inv_h, cells, strides,
                        idx, w, dw)
    return first_of(bad)


@njit(cache=True)
def _block(axis, nodes, dims, start, stop, x, data, lower, inv_h, cells, strides, idx, w, dw):
    """The particles start..stop-1 (a parallel kernel's block, solver/kernels.py)."""
    dim, support = len(dims), nodes.ndim
    base = np.empty(dim, dtype=np.int64)
    w1 = np.empty((dim, support))
    g1 = np.empty((dim, support))
    for p in range(start, stop):
        for a in range(dim):
            first = axis((x[p, a] - lower[a]) * inv_h[a], a, p, cells[a], inv_h[a], data, w1, g1)
            if first < 0:
                return p
            base[a] = first
        scatter(p, nodes, dims, base, w1, g1, strides, idx, w, dw)
    return -1


@njit(cache=True)
def scatter(p, nodes, dims, base, w1, g1, strides, idx, w, dw):
    """Fill idx[p], w[p], dw[p] with the tensor products of the 1D weights (the support
    nodes.ndim and the dimension len(dims) compile-time constants: the divisions below
    become multiplications)."""
    dim, support = len(dims), nodes.ndim
    nk = support**dim
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
