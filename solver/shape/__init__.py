"""Shape (weighting) functions, registered by name.

A shape function module provides `SUPPORT` (nodes per axis that a particle
touches) and a numba kernel

    weights(spec, x, lower, inv_h, cells, strides, idx, w, dw, blocks) -> int

filling, for every particle p and every node k of its stencil, the flat node
index idx[p, k], the weight w[p, k] and the gradient dw[p, k, :], in `blocks`
contiguous blocks of particles run on as many threads (solver/threads.py; any
count gives the same bits). It returns the index of the first particle outside
the grid (or whose stencil would need a node beyond the grid), or -1. `spec` makes the dimension and stencil size
compile-time constants (kernels.stencil_spec). Stencil node k has the per-axis
offsets (k // SUPPORT**a) % SUPPORT from the particle's first node, axis 0
fastest. Node numbers must be sum_a i_a * strides[a] with i_a the node's index
along axis a of the whole grid (lower, cells), and a particle in cell i may touch
nodes i - (S-1)//2 ... i + ceil(S/2) only (S = SUPPORT): with several processes
the kernel is called with the strides of a process's slab of the grid
(solver/parallel). The transfer kernels only ever see idx, w and dw, so they are
the same for every shape function.

A function that needs per-particle data (GIMP's particle sizes) also provides
`prepare(scene, particles)`, which allocates it in `Particles.extra`, and
`evaluate(spec, x, particles, grid, stencil, blocks)`, which calls its kernel with it.
Callers use the module-level `prepare` and `evaluate` below, which fall back to
the plain kernel.

| name | SUPPORT | module |
|---|---|---|
| linear | 2 | hat functions |
| gimp | 3 | uGIMP |
| cpgimp | 3 | cpGIMP (GIMP boxes stretched by diag F) |
| quadratic_bspline | 3 | quadratic B-splines |
| cubic_bspline | 4 | cubic B-splines, boundary-modified |
| bernstein | 3 | quadratic Bernstein, elements of two cells (TLMPM only) |
"""
from __future__ import annotations

from types import ModuleType, SimpleNamespace

import numba
import numpy as np

from solver.shape.kernels import bernstein, cubic_bspline, gimp, linear, quadratic_bspline

# cpGIMP is GIMP with boxes that follow the stretch: the same kernel, another evaluate.
_cpgimp = SimpleNamespace(__name__="solver.shape.cpgimp", SUPPORT=gimp.SUPPORT, weights=gimp.weights,
                          prepare=gimp.prepare, evaluate=gimp.evaluate_contiguous)

REGISTRY: dict[str, ModuleType | SimpleNamespace] = {
    "linear": linear,
    "gimp": gimp,
    "cpgimp": _cpgimp,
    "quadratic_bspline": quadratic_bspline,
    "cubic_bspline": cubic_bspline,
    "bernstein": bernstein,
}


def get(name: str) -> ModuleType:
    try:
        return REGISTRY[name]
    except KeyError:
        raise ValueError(f"shape function {name!r} is not implemented; known: {sorted(REGISTRY)}") from None


def prepare(module, scene, particles) -> None:
    """Allocate the per-particle data the function needs (nothing for most)."""
    if hasattr(module, "prepare"):
        module.prepare(scene, particles)


def evaluate(module, spec, x: np.ndarray, particles, grid, stencil) -> int:
    """Weights and gradients at positions x (the particles' current or reference
    positions) into the stencil; the first particle outside the grid, or -1.
    One block of particles per thread of this process (set by threads.configure)."""
    blocks = numba.get_num_threads()
    if hasattr(module, "evaluate"):
        return module.evaluate(spec, x, particles, grid, stencil, blocks)
    return module.weights(spec, x, grid.lower, grid.inv_h, grid.cells, grid.strides,
                          stencil.idx, stencil.w, stencil.dw, blocks)
