"""Shape (weighting) functions, registered by name.

A shape function module provides `SUPPORT` (nodes per axis that a particle
touches) and a numba kernel

    weights(spec, x, lower, inv_h, cells, strides, idx, w, dw) -> int

filling, for every particle p and every node k of its stencil, the flat node
index idx[p, k], the weight w[p, k] and the gradient dw[p, k, :]. It returns the
index of the first particle outside the grid, or -1. Node numbers must be
sum_a i_a * strides[a] with i_a the node's index along axis a of the whole grid
(lower, cells), and a particle in cell i may touch nodes i - (S-1)//2 ...
i + ceil(S/2) only (S = SUPPORT): with several processes the kernel is called
with the strides of a process's slab of the grid (solver/parallel). `spec` makes the
dimension and stencil size compile-time constants (kernels.stencil_spec). The transfer kernels only
ever see idx, w and dw, so they are the same for every shape function.
"""
from __future__ import annotations

from types import ModuleType

from solver.shape import linear

REGISTRY: dict[str, ModuleType] = {"linear": linear}


def get(name: str) -> ModuleType:
    try:
        return REGISTRY[name]
    except KeyError:
        raise ValueError(f"shape function {name!r} is not implemented; known: {sorted(REGISTRY)}") from None
