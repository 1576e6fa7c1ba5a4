"""The largest stable time step of a scene at t = 0, decided before anything is allocated.

A limit is a function scene -> Limit | None; the scene's limit is the smallest of
`LIMITS`. Today: the wave speed limit of explicit MPM (review eq. 2.73 with CFL = 1),
dt <= min h / max over bodies (c_dil + largest initial speed). A physics with a
limit of its own (heat conduction: rho c h^2 / (2 d k)) appends its function to
`LIMITS`. The adaptive step starts from cfl times the wave limit (solver/summary.py);
validation refuses a fixed `time.dt` above the limit unless `time.allow_unstable_dt`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from solver.expressions import compile_expression
from solver.scene import SPACE_VARIABLES, TIME_VARIABLES
from solver.pore_fluid_schema import diffusion_time_step, undrained_wave_speed
from solver.thermal_schema import conduction_time_step

_SAMPLES_PER_AXIS = 17  # points per axis of a body's box where initial velocities are sampled
_TIME_SAMPLES = 101  # instants in [0, end] where prescribed velocities are sampled


@dataclass(frozen=True)
class Limit:
    dt: float       # the largest stable step
    reason: str     # what sets it, for the error message


def fastest_signal(scene) -> float:
    """max over bodies of (dilatational wave speed + largest initial or prescribed speed)."""
    return max(_wave_speed(scene, body) + _largest_speed(scene, body) for body in scene.bodies)


def wave_limit(scene) -> Limit | None:
    fastest = fastest_signal(scene)
    if fastest <= 0:
        return None
    h = min(scene.cell_sizes())
    return Limit(h / fastest, f"h / (c + |v|) = {h:.6g} / {fastest:.6g} (the fastest wave plus the largest "
                              f"initial speed)")


def conduction_limit(scene) -> Limit | None:
    """Explicit conduction's rho c h^2 / (2 d k) (solver/thermal_schema.py), where heat conducts."""
    found = conduction_time_step(scene)
    return None if found is None else Limit(found[0], f"the conduction limit rho c h^2 / (2 d k) of material "
                                                      f"{found[1]!r}")


def pore_pressure_limit(scene) -> Limit | None:
    """The pore pressure's diffusion limit h^2 / (2 d k K_w / (n rho_w g_n)) (solver/pore_fluid_schema.py)."""
    found = diffusion_time_step(scene)
    return None if found is None else Limit(found[0], f"the pore pressure's diffusion limit h^2 n rho_w g_n / "
                                                      f"(2 d k K_w) of material {found[1]!r}")


LIMITS: list[Callable] = [wave_limit, conduction_limit, pore_pressure_limit]


def stable_limit(scene) -> Limit | None:
    """The smallest of the limits, None when nothing limits the step."""
    limits = [limit for make in LIMITS if (limit := make(scene)) is not None]
    return min(limits, key=lambda limit: limit.dt, default=None)


def time_step_problems(scene) -> list[tuple[str, str]]:
    """A fixed time.dt above the stable limit, unless the scene allows it."""
    dt = scene.time.dt
    if dt is None or scene.time.allow_unstable_dt:
        return []
    limit = stable_limit(scene)
    if limit is None or dt <= limit.dt * (1 + 1e-9):
        return []
    return [("time.dt", f"{dt:.6g} is above this scene's stability limit {limit.dt:.6g} ({limit.reason}); "
                        f"use a smaller dt, leave dt out for an adaptive step, or set "
                        f"time.allow_unstable_dt to true to run it anyway")]


def _wave_speed(scene, body) -> float:
    """The body's P-wave speed: the material's initial one, from the scene where the material
    needs it (`initial_wave_speed_in(scene, body)`: Cam-Clay's stiffness follows the geostatic
    stress); a saturated soil's with the pore fluid's stiffness."""
    material = scene.materials[body.material]
    in_scene = getattr(material, "initial_wave_speed_in", None)
    dry = in_scene(scene, body) if in_scene is not None else material.initial_wave_speed(body)
    return undrained_wave_speed(material, dry)


def _largest_speed(scene, body) -> float:
    """Largest initial (or prescribed) speed, sampled on the points of a lattice over the
    body's box that are inside the body (or over [0, end] for a prescribed velocity): a
    field such as a vortex's grows fast outside its ring, where no particle is."""
    if body.velocity is not None:
        values = {"t": np.linspace(0.0, scene.time.end, _TIME_SAMPLES)}
        return _largest_norm(body.velocity, TIME_VARIABLES, values, scene.expressions)
    if body.initial_velocity is None:
        return 0.0
    points = _sample_points(body.geometry.shape())
    values = {name: points[:, a] for a, name in enumerate(SPACE_VARIABLES[:points.shape[1]])}
    return _largest_norm(body.initial_velocity, SPACE_VARIABLES, values, scene.expressions)


def _sample_points(region) -> np.ndarray:
    """Points of a lattice over the region's box that are inside it (all of them if none is);
    a body given as its particles (`points`) is sampled at those."""
    positions = getattr(region, "positions", None)
    if positions is not None:
        return positions
    lower, upper = region.bounding_box()
    lattice = np.meshgrid(*(np.linspace(lo, up, _SAMPLES_PER_AXIS) for lo, up in zip(lower, upper)), indexing="ij")
    points = np.stack([axis.ravel() for axis in lattice], axis=1)
    inside = region.contains(points)
    return points[inside] if np.any(inside) else points


def _largest_norm(components: list[float | str], variables: tuple[str, ...], values: dict,
                  definitions: dict | None = None) -> float:
    squares = 0.0
    for component in components:
        if component is None:   # a free axis of a rigid body
            continue
        value = compile_expression(component, variables, definitions).evaluate(**values) if isinstance(component, str) else component
        squares = squares + np.square(value)
    largest = float(np.max(np.sqrt(squares)))
    return largest if math.isfinite(largest) else 0.0
