"""Shape (weighting) functions, registered by name.

A shape function is declared in solver/shape/<module>.py: a `ShapeFunction`
(solver/shape/registry.py) with its name, `support` (SUPPORT: nodes per axis
that a particle touches), APIC constant, the formulations and transfers it
allows and what it needs of the grid. `REGISTRY` maps the names to these
declarations; the scene's `shape_function` values, `capabilities.SHAPE_FUNCTIONS`
and the summary's memory estimate are built from it, and none of it loads numba.
`get(name)` imports the kernel module it names (solver/shape/kernels/), which
provides a numba kernel

    weights(spec, x, lower, inv_h, cells, strides, idx, w, dw, blocks) -> int

filling, for every particle p and every node k of its stencil, the flat node
index idx[p, k], the weight w[p, k] and the gradient dw[p, k, :], in `blocks`
contiguous blocks of particles run on as many threads (solver/threads.py; any
count gives the same bits). It returns the index of the first particle outside
the grid (or whose stencil would need a node beyond the grid), or -1. `spec` makes the dimension and stencil size
compile-time constants (kernels.stencil_spec). Stencil node k has the per-axis
offsets (k // S**a) % S from the particle's first node, axis 0 fastest, S the
stencil's nodes per axis: SUPPORT, or for CPDI COMPACT_SUPPORT while the run is on its
compact stencil and as many as `support_needed` said once a domain outgrew SUPPORT
(the kernel tells them apart by the length of spec's node tuple). Node numbers must be sum_a i_a * strides[a] with i_a the node's index
along axis a of the whole grid (lower, cells), and a particle in cell i may touch
nodes i - (S-1)//2 ... i + ceil(S/2) only (S = SUPPORT): with several processes
the kernel is called with the strides of a process's slab of the grid
(solver/parallel). The transfer kernels only ever see idx, w and dw, so they are
the same for every shape function.

A function that needs per-particle data (GIMP's particle sizes) also provides
`prepare(scene, particles)`, which allocates it in `Particles.extra`, and
`evaluate(spec, x, particles, grid, stencil, blocks)`, which calls its kernel with it.
Callers use the module-level `prepare` and `evaluate` below, which fall back to
the plain kernel. A function that may refuse a particle inside the grid (CPDI: a
domain larger than its stencil) provides `failure(x, particles, grid, index)`,
the diagnostic the step reports instead of "outside the grid", and one whose
domains may outgrow any fixed stencil (CPDI) provides `support_needed(x, particles,
grid)`, the nodes per axis its largest domain needs, which the step widens the
stencil to (solver/step/general.py).
"""
from __future__ import annotations

from importlib import import_module
from types import SimpleNamespace

import numpy as np

from solver import capabilities
from solver.shape.registry import ShapeFunction

__all__ = ["BUILTIN", "REGISTRY", "ShapeFunction", "evaluate", "failure", "get", "prepare", "support_needed"]

# The declaration modules, in the order the scene lists the names (its error
# messages and JSON schema enumerate them in this order).
BUILTIN = ("linear", "gimp", "cubic_bspline", "quadratic_bspline", "bernstein", "cpdi")

REGISTRY: dict[str, ShapeFunction] = {
    declared.name: declared
    for module in BUILTIN
    for declared in import_module(f"solver.shape.{module}").SHAPE_FUNCTIONS
}
capabilities.SHAPE_FUNCTIONS.read_from(REGISTRY.keys)


def get(name: str) -> SimpleNamespace:
    """The kernels of shape function `name`: SUPPORT, weights, and prepare and evaluate
    where it has them (imported now: this loads numba)."""
    try:
        declared = REGISTRY[name]
    except KeyError:
        raise ValueError(f"shape function {name!r} is not implemented; known: {sorted(REGISTRY)}") from None
    module = import_module(declared.kernels)
    functions = {"weights": module.weights, "prepare": getattr(module, "prepare", None),
                 "evaluate": getattr(module, declared.evaluate, None), "failure": getattr(module, "failure", None),
                 "support_needed": getattr(module, "support_needed", None),
                 "hook": getattr(module, declared.hook, None) if declared.hook else None}
    return SimpleNamespace(__name__=f"{module.__name__}:{name}", SUPPORT=declared.support,
                           COMPACT_SUPPORT=declared.compact_support,
                           **{key: f for key, f in functions.items() if f is not None})


def prepare(module, scene, particles) -> None:
    """Allocate the per-particle data the function needs (nothing for most)."""
    if hasattr(module, "prepare"):
        module.prepare(scene, particles)


def failure(module, x: np.ndarray, particles, grid, index: int) -> tuple[str, str] | None:
    """Why the weights refused particle `index` when its position is inside the grid
    (a function whose stencil may not reach, CPDI's large domains): (quantity, detail);
    None for a particle outside the grid (the caller says so). `grid`: the whole grid's
    lower, inv_h and cells."""
    if hasattr(module, "failure"):
        return module.failure(x, particles, grid, index)
    return None


def support_needed(module, x: np.ndarray, particles, grid) -> int | None:
    """The stencil's nodes per axis that the particles' domains need (CPDI); None for a
    function whose stencil is fixed. `grid`: the whole grid's lower, inv_h and cells."""
    if hasattr(module, "support_needed"):
        return module.support_needed(x, particles, grid)
    return None


def evaluate(module, spec, x: np.ndarray, particles, grid, stencil) -> int:
    """Weights and gradients at positions x (the particles' current or reference
    positions) into the stencil; the first particle outside the grid, or -1.
    One block of particles per thread of this process (set by threads.configure)."""
    import numba   # here: the declarations above load with the scene, which must not load numba

    blocks = numba.get_num_threads()
    if hasattr(module, "evaluate"):
        return module.evaluate(spec, x, particles, grid, stencil, blocks)
    return module.weights(spec, x, grid.lower, grid.inv_h, grid.cells, grid.strides,
                          stencil.idx, stencil.w, stencil.dw, blocks)
