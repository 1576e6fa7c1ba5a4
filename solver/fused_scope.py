"""Which scenes the fused kernels (solver/fused.py) step, decided without loading numba:
the service's run-time estimates (solver/cost.py) ask it too."""
from __future__ import annotations

from solver import shape
from solver.pore_fluid_schema import saturated
from solver.thermal_schema import conducts

FUSED_SHAPES = frozenset({"linear", "quadratic_bspline"})   # the shape modules whose 1D weights `fused._axis` calls


def supports(scene) -> bool:
    """Whether the scene's step is one the fused kernels implement: ULMPM, USL or MUSL,
    linear or quadratic B-spline weights, 2D or 3D, no axisymmetry, rigid body, heat
    conduction with USL (its one G2P pass moves x_p before the flux gather, which needs
    x_p^t: MUSL's kinematics pass has it) or with frictional walls (their heat goes into
    T~_I^{t+dt} before the particles take it: solver/thermal.py), and for APIC and MLS a shape
    function whose D_p is a constant times h^2 (its declared `apic_d`). Per-body contact fields
    are fused with the mass-gradient normals ([R] 5.12, scattered by the fused P2G; the density
    gradient's cell pass reads the particles apart) and without conduction (the fields'
    exchange and the frictional heat enter T~_I^{t+dt} before the particles take it, as the
    frictional walls' do); rigid bodies, which contact also meets, are not fused at all. A
    saturated soil's pore passes form their own stencils (solver/pore_kernels.py), on the
    grid's one field: not with contact fields."""
    method = scene.method
    return (method.formulation == "ulmpm" and method.scheme in ("usl", "musl")
            and method.shape_function in FUSED_SHAPES and not scene.axisymmetric
            and scene.dimension in (2, 3)
            and not any(m.model == "rigid" for m in scene.materials.values())
            and not (saturated(scene) and scene.contact.fields)   # its passes know one field
            and (method.scheme == "musl" or not conducts(scene))
            and not (conducts(scene) and _friction_walls(scene))   # their heat enters T~ before the remap
            and (not scene.contact.fields or _fused_contact(scene))
            and (method.transfer not in ("apic", "mls") or shape.REGISTRY[method.shape_function].apic_d is not None))


def _friction_walls(scene) -> bool:
    return any(getattr(bc, "mode", None) == "friction" for bc in scene.boundary_conditions)


def _fused_contact(scene) -> bool:
    return scene.contact.normals == "mass_gradient" and not conducts(scene)
