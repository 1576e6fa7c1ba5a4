"""The particle loop of a tensor-product shape function, written once and generated per
shape function by `tensor.kernels` (solver/generated.py): the generated copy imports the
function's own `axis`, so `axis` is a global of the kernel and numba caches it. Passed as
an argument instead, a function makes a cache entry that no later process finds (numba
types it by the object), so every run compiled the kernel again (about 3 s) and the cache
index grew without bound.

This file runs as it is for quadratic B-splines (the import line below); `tensor.kernels`
replaces that line for the other shape functions.
"""
import numpy as np
from solver.jit import njit, prange

from solver.shape.kernels.tensor import scatter
from solver.threads import block_bounds, first_of

from solver.shape.kernels.quadratic_bspline import axis  # the shape function's own 1D weights


@njit(parallel=True, cache=True)
def weights(nodes, spec, x, data, lower, inv_h, cells, strides, idx, w, dw, blocks):
    """idx, w, dw of every particle (solver/shape/__init__.py); the first particle outside
    the grid, or -1. `nodes`: an empty array whose rank is the support, a compile-time
    constant (a runtime support made the divisions of the tensor product cost 2-5x)."""
    dims = spec[0]
    if nodes.ndim ** len(dims) != idx.shape[1]:
        raise ValueError("the kernel's support does not match the stencil's (the declared support)")
    bounds = block_bounds(x.shape[0], blocks)
    bad = np.empty(blocks, dtype=np.int64)
    for t in prange(blocks):
        bad[t] = _block(nodes, dims, bounds[t], bounds[t + 1], x, data, lower, inv_h, cells, strides, idx, w, dw)
    return first_of(bad)


@njit(cache=True)
def _block(nodes, dims, start, stop, x, data, lower, inv_h, cells, strides, idx, w, dw):
    """The particles start..stop-1 (a parallel kernel's block, solver/kernels.py)."""
    dim, support = len(dims), nodes.ndim
    base = np.empty(dim, dtype=np.int64)
    w1 = np.empty((dim, support))
    g1 = np.empty((dim, support))
    for p in range(np.uint64(start), np.uint64(stop)):   # unsigned: no wrap-around test (docs/internals.md)
        for a in range(dim):
            first = axis((x[p, a] - lower[a]) * inv_h[a], a, p, cells[a], inv_h[a], data, w1, g1)
            if first < 0:
                return np.int64(p)
            base[a] = first
        scatter(p, nodes, dims, base, w1, g1, strides, idx, w, dw)
    return -1
