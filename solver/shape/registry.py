"""The declaration of a shape function: what the scene validation, the summary and
the step need to know about it without loading its numba kernel."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class ShapeFunction:
    """One shape function (the scene's ``method.shape_function`` value `name`)."""

    name: str
    support: int  # nodes per axis that one particle touches
    kernels: str  # module with the numba kernel `weights` (and `prepare`, `evaluate`), imported on first use
    evaluate: str = "evaluate"  # the kernel module's evaluate function for this name (cpGIMP: evaluate_contiguous)
    # c in D_p = c h^2 per axis (APIC's inertia, solver/transfer.py) where D_p is the same at
    # every position; None where it varies (boundary-modified, particle-size dependent, ...)
    apic_d: float | None = None
    apic: bool = True  # transfer 'apic' may use it
    apic_refusal: str = ""  # the validation message where it may not
    # C1 (its gradient is continuous, and vanishes where the weight does): transfer 'mls',
    # whose gradient w D_p^-1 (x_I - x_p) stands in for grad w, may use it (solver/transfer.py)
    smooth: bool = False
    formulations: frozenset[str] = frozenset({"ulmpm", "tlmpm"})
    formulation_refusal: str = ""  # the validation message for the other formulations
    least_cells: int = 1  # cells per axis the grid needs
    even_cells: bool = False  # its elements span two cells: the grid gets an even number per axis
    end_margin: float = 0.0  # cells a body keeps from the grid ends (no boundary-modified variant)
    axisymmetric: bool = True  # usable in axisymmetric scenes
    axisymmetric_refusal: str = ""  # the validation message where it is not
    dimensions: frozenset[int] = frozenset({1, 2, 3})  # the scene dimensions it has
    dimension_refusal: str = ""  # the validation message for the others
    hook: str = ""  # the kernel module's factory of a step hook it needs (cpdi_q4: its corners move), or none
    # Nodes per axis of the stencil a run starts with where fewer than `support` do for most
    # particles (CPDI: 3, a domain within two cells per axis); the first particle that needs
    # more widens the stencil for the rest of the run (solver/step/general.py). 0: none.
    compact_support: int = 0
    # Its weights depend on a particle's own data (GIMP's sizes, CPDI's domains), not on the
    # position alone: no integral of N_I over the grid (a gas's density from the grid) is defined.
    per_particle_data: bool = False
