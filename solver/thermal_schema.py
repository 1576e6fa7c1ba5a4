"""The thermal part of a scene, read without numba (the scene's validation and the
solver both use it): which materials conduct or expand, the explicit conduction
step's stability limit, and the validation rules of the thermal keys and
boundary conditions (solver/scene_rules.py calls `thermal_problems`).

The limit of the forward-Euler conduction step on a grid of cells h_a, with the
lumped capacity C_I, is dt <= 1 / (2 kappa sum_a 1/h_a^2), kappa = k / (rho c):
rho c h^2 / (2 d k) for cubic cells, as [R] 5.3.3 states it for 1D.
"""
from __future__ import annotations

import math

from solver.schema import ElasticMaterial

THERMAL_KEYS = ("thermal_conductivity", "specific_heat", "thermal_expansion")
# the `type` of the scene's thermal boundary conditions (solver/scene.py)
THERMAL_CONDITIONS = ("temperature", "heat_flux", "convection")


def conducts(scene) -> bool:
    """Whether heat conducts anywhere in the scene (some material has thermal_conductivity > 0)."""
    return any(m.conducts for m in scene.materials.values())


def expands(scene) -> bool:
    """Whether some material has a thermal expansion coefficient."""
    return any(getattr(m, "thermal_expansion", None) for m in scene.materials.values())


def _inverse_square(h: float) -> float:
    """1 / h^2, written so (its bits are the time step's, which the regression cases hold);
    0 where h**2 overflows (h past 1e154, where (1/h)^2 underflows to 0 anyway)."""
    try:
        return 1.0 / h**2
    except OverflowError:
        return 0.0


def conduction_time_step(scene) -> tuple[float, str] | None:
    """(the largest stable dt of conduction, the material that sets it), or None without conduction."""
    inverse_h2 = sum(_inverse_square(h) for h in scene.cell_sizes())
    best = None
    for body in scene.bodies:
        material = scene.materials.get(body.material)
        if material is None or not material.conducts or material.specific_heat is None:
            continue
        density = body.initial_density or getattr(material, "density", None)
        if not density:
            continue
        conductance = 2.0 * material.thermal_conductivity * inverse_h2
        limit = density * material.specific_heat / conductance if conductance > 0 else math.inf
        if best is None or limit < best[0]:
            best = (limit, body.material)
    return best


def thermal_problems(scene, length_ok) -> list[tuple[str, str]]:
    """The thermal keys of the materials and the thermal boundary conditions."""
    problems: list[tuple[str, str]] = []
    for name, material in scene.materials.items():
        path = f"materials.{name}"
        if material.model == "rigid":
            problems += [(f"{path}.{key}", "is not supported yet for rigid bodies (they carry no mass)")
                         for key in THERMAL_KEYS if getattr(material, key) is not None]
            continue
        if material.conducts and material.specific_heat is None:
            problems.append((f"{path}.specific_heat", "required with thermal_conductivity > 0"))
        if material.thermal_expansion and not isinstance(material, ElasticMaterial):
            problems.append((f"{path}.thermal_expansion", f"is not supported yet for model {material.model!r} "
                                                          "(the solid models only)"))
    heated = conducts(scene)
    for i, condition in enumerate(scene.boundary_conditions):
        if condition.type not in THERMAL_CONDITIONS:
            continue
        path = f"boundary_conditions[{i}]"
        if not heated:
            problems.append((f"{path}.type", f"{condition.type!r} needs a material with thermal_conductivity > 0"))
        if condition.face is not None and "xyz".index(condition.face[0]) >= scene.dimension:
            problems.append((f"{path}.face", f"{condition.face!r} is not a face of a {scene.dimension}D grid"))
        where = getattr(condition, "where", None)
        if where is not None:
            length_ok(f"{path}.where.lower", where.lower)
            length_ok(f"{path}.where.upper", where.upper)
    return problems   # (a fixed dt above the conduction limit: solver/stability.py)
