"""The two-phase (saturated soil) part of a scene, read without numba: which materials
carry a pore fluid, the limits the fluid puts on the explicit step, and the validation
rules of `pore_fluid`, `initial_pore_pressure` and the `pore_pressure` conditions
(solver/scene_rules.py calls `pore_fluid_problems`; the physics is solver/pore_fluid.py).

Two limits (solver/stability.py takes the smaller with the others):
- the P-wave of the undrained mixture, c = sqrt(c_dry^2 + (K_w / n) / rho): the fluid
  stiffens the skeleton against volume change;
- the pore pressure's diffusion, forward Euler on the lumped storage n / K_w:
  dt <= h^2 / (2 sum_a (h/h_a)^2 D), D = k K_w / (n rho_w g_n)  (cubic cells: h^2 / (2 d D)),
  the conduction limit with the storage in place of rho c.
"""
from __future__ import annotations

import math

import numpy as np

G_N = 9.81   # m/s^2: the gravity Darcy's k is measured under, whatever the scene's gravity
# models with no skeleton for the fluid to fill
_NOT_SOILS = ("rigid", "fluid", "ideal_gas")


def saturated(scene) -> bool:
    """Whether some material of the scene has a pore fluid."""
    return any(getattr(m, "pore_fluid", None) is not None for m in scene.materials.values())


def mobility(fluid) -> float:
    """k / (rho_w g_n): Darcy's flux per unit gradient of the pore pressure's excess, m^2/(Pa s)."""
    return fluid.hydraulic_conductivity / (fluid.density * G_N)


def _inverse_squares(scene) -> float:
    return sum(1.0 / h**2 if h < 1e150 else 0.0 for h in scene.cell_sizes())


def diffusion_time_step(scene) -> tuple[float, str] | None:
    """(the largest stable dt of the pore pressure's diffusion, the material that sets it), or None."""
    best = None
    for name, material in scene.materials.items():
        fluid = getattr(material, "pore_fluid", None)
        if fluid is None:
            continue
        rate = 2.0 * mobility(fluid) * fluid.storage_modulus * _inverse_squares(scene)
        limit = 1.0 / rate if rate > 0 else math.inf
        if best is None or limit < best[0]:
            best = (limit, name)
    return best


def undrained_wave_speed(material, dry: float) -> float:
    """The P-wave speed of the saturated mixture: sqrt(c_dry^2 + (K_w / n) / rho), c_dry the
    skeleton's, rho the material's (mixture) density."""
    density = getattr(material, "density", None)
    if material.pore_fluid is None or not density:
        return dry
    return math.sqrt(dry * dry + material.pore_fluid.storage_modulus / density)


def pore_fluid_problems(scene, length_ok) -> list[tuple[str, str]]:
    """The pore fluid's materials, bodies and conditions, and what the two-phase step does not support."""
    problems: list[tuple[str, str]] = []
    for name, material in scene.materials.items():
        if material.pore_fluid is not None and material.model in _NOT_SOILS:
            problems.append((f"materials.{name}.pore_fluid", f"not for a {material.model!r} material (a pore fluid "
                                                            "fills a solid skeleton: a soil model)"))
    wet = saturated(scene)
    if wet:
        problems += _unsupported(scene)
    for i, body in enumerate(scene.bodies):
        if body.initial_pore_pressure is None:
            continue
        material = scene.materials.get(body.material)
        path = f"bodies[{i}].initial_pore_pressure"
        if material is not None and material.pore_fluid is None:
            problems.append((path, f"material {body.material!r} has no pore_fluid"))
        if body.initial_pore_pressure.type == "hydrostatic":
            vertical = scene.dimension - 1
            if any(g for a, g in enumerate(scene.gravity or []) if a != vertical):
                problems.append((path, f"a hydrostatic pore pressure needs gravity along {'xyz'[vertical]} "
                                       f"(the height axis) or none (gravity is {scene.gravity})"))
    for i, condition in enumerate(scene.boundary_conditions):
        if condition.type != "pore_pressure":
            continue
        path = f"boundary_conditions[{i}]"
        if not wet:
            problems.append((f"{path}.type", "'pore_pressure' needs a material with a pore_fluid"))
        if condition.face is not None and "xyz".index(condition.face[0]) >= scene.dimension:
            problems.append((f"{path}.face", f"{condition.face!r} is not a face of a {scene.dimension}D grid"))
        if condition.where is not None:
            length_ok(f"{path}.where.lower", condition.where.lower)
            length_ok(f"{path}.where.upper", condition.where.upper)
    return problems


def _unsupported(scene) -> list[tuple[str, str]]:
    """What the two-phase step (ULMPM with USL or MUSL, one grid field) does not run yet."""
    first = next(name for name, m in scene.materials.items() if m.pore_fluid is not None)
    path = f"materials.{first}.pore_fluid"
    problems = []
    if scene.method.formulation != "ulmpm":
        problems.append((path, f"is not supported yet with formulation {scene.method.formulation!r} (ulmpm only)"))
    if scene.method.scheme == "usf":   # (a Terzaghi column went unstable: the pore force lags the stress)
        problems.append((path, "is not supported yet with scheme 'usf' (usl and musl)"))
    if scene.dimension == 1:
        problems.append((path, "is not supported yet in 1D (2D plane strain and 3D)"))
    if scene.contact.fields:
        problems.append((path, f"is not supported yet with contact model {scene.contact.model!r} "
                               "(one grid field only)"))
    return problems


def hydrostatic_gravity(scene) -> float:
    """|g| along the height axis (y in 2D, z in 3D); 0 without gravity."""
    gravity = scene.gravity or []
    vertical = scene.dimension - 1
    return abs(float(gravity[vertical])) if len(gravity) > vertical else 0.0


def initial_pore_pressure(scene, body, x: np.ndarray) -> np.ndarray:
    """The pore pressure at t = 0 at the points `x` of `body`: 0 without `initial_pore_pressure`,
    rho_w |g| (water_table - height) below the water table ("hydrostatic", 0 above), or uniform."""
    spec = body.initial_pore_pressure
    if spec is None:
        return np.zeros(x.shape[0])
    if spec.type == "uniform":
        return np.full(x.shape[0], float(spec.pressure))
    fluid = scene.materials[body.material].pore_fluid
    height = x[:, scene.dimension - 1]
    return fluid.density * hydrostatic_gravity(scene) * np.maximum(spec.water_table - height, 0.0)
