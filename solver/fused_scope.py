"""Which scenes the fused kernels (solver/fused.py) step, decided without loading numba:
the service's run-time estimates (solver/cost.py) ask it too."""
from __future__ import annotations

from solver import shape
from solver.thermal_schema import conducts

FUSED_SHAPES = frozenset({"linear", "quadratic_bspline"})   # the 1D weights `_axis` writes out


def supports(scene) -> bool:
    """Whether the scene's step is one the fused kernels implement: ULMPM, USL or MUSL,
    linear or quadratic B-spline weights, 2D or 3D, no axisymmetry, rigid body, heat
    conduction with USL (its one G2P pass moves x_p before the flux gather, which needs
    x_p^t: MUSL's kinematics pass has it) or with frictional walls (their heat goes into
    T~_I^{t+dt} before the particles take it: solver/thermal.py), per-body contact fields, and for APIC and MLS a shape function whose D_p
    is a constant times h^2 (its declared `apic_d`)."""
    method = scene.method
    return (method.formulation == "ulmpm" and method.scheme in ("usl", "musl")
            and method.shape_function in FUSED_SHAPES and not scene.axisymmetric
            and scene.dimension in (2, 3)
            and not any(m.model == "rigid" for m in scene.materials.values())
            and (method.scheme == "musl" or not conducts(scene))
            and not (conducts(scene) and _friction_walls(scene))   # their heat enters T~ before the remap
            and not scene.contact.fields   # the per-body fields need the stored stencil (solver/contact.py)
            and (method.transfer not in ("apic", "mls") or shape.REGISTRY[method.shape_function].apic_d is not None))


def _friction_walls(scene) -> bool:
    return any(getattr(bc, "mode", None) == "friction" for bc in scene.boundary_conditions)
