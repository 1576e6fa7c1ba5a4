"""The `ideal_gas` material: an ideal gas with artificial viscosity ([R] 5.4.2; the
energy and stress update is solver/materials/kernels/ideal_gas.py). It has no
density of its own: each body gives its initial density and pressure."""

import math
from typing import Annotated, Any, ClassVar, Literal

import numpy as np
from pydantic import Field, Strict

from solver.materials.registry import MaterialType, StateVariable
from solver.schema import BaseMaterial, NonNegative, SceneModel


class ArtificialViscosity(SceneModel):
    """q = rho L_e (quadratic L_e D_kk^2 - linear a D_kk) in compression ([R] eq. 5.35):
    von Neumann-Richtmyer's quadratic and Landshoff's linear term; 0 and 0 turn it off.
    The defaults are the usual bulk viscosity of explicit codes (1.5^2 and 0.06)."""

    quadratic: NonNegative = 2.25
    linear: NonNegative = 0.06


class IdealGas(BaseMaterial):
    """Ideal gas; each body gives its initial density and pressure."""

    model: Literal["ideal_gas"]
    gamma: Annotated[float, Strict(), Field(gt=1)] = 1.4
    artificial_viscosity: ArtificialViscosity = Field(default_factory=ArtificialViscosity)
    # At the start of each step the particles take the grid's density (solver/gas_density.py):
    # their volumes J V0 drift from the room they take where a gas thins to about a particle a
    # cell. None: wherever the scene allows it (grid_density_refusal below).
    density_from_grid: Annotated[bool, Strict()] | None = None
    # A gas expands to about one particle per cell (Sod's left plateau: 1.3 of the 3 it started
    # with), where the C1 cubic splines are the most accurate: L1 density error 0.0034 at cfl 0.5
    # against linear hats' 0.012 (with the density from the grid; docs/benchmarks.md "Sod").
    method_defaults: ClassVar[dict[str, Any]] = {"shape_function": "cubic_bspline"}
    body_state_keys: ClassVar[tuple[str, ...]] = ("initial_density", "initial_pressure")

    def sound_speed(self, density: float, pressure: float) -> float:
        """sqrt(gamma p / rho); the wave speed depends on the body's state."""
        return math.sqrt(self.gamma * pressure / density)

    def initial_wave_speed(self, body) -> float:
        return self.sound_speed(body.initial_density, body.initial_pressure)

    def scene_problems(self, path: str, scene) -> list[tuple[str, str]]:
        refusal = grid_density_refusal(scene) if self.density_from_grid else None
        return [(f"{path}.density_from_grid", f"true {refusal}")] if refusal else []


def grid_density_refusal(scene) -> str | None:
    """Why the scene's gases cannot take their density from the grid (solver/gas_density.py), or None."""
    from solver import shape

    method = scene.method
    if shape.REGISTRY[method.shape_function].per_particle_data:
        return (f"the nodes' volumes need weights of the position alone, not {method.shape_function!r}'s "
                "particle domains")
    if method.formulation != "ulmpm":
        return "needs formulation 'ulmpm' (TLMPM's grid is the reference configuration)"
    if scene.axisymmetric:
        return "is not available in axisymmetric scenes (the nodes' volumes are rings)"
    return None


def takes_grid_density(scene, material) -> bool:
    """Whether a material is a gas that takes its density from the grid: as it says, else where it can."""
    wanted = getattr(material, "density_from_grid", False)
    return bool(wanted) if wanted is not None else grid_density_refusal(scene) is None


def grid_density(scene) -> bool:
    """Whether a scene has a gas that takes its density from the grid (its energy term)."""
    return any(takes_grid_density(scene, material) for material in scene.materials.values())


def body_state(scene, body: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(density, pressure) of each particle at t = 0, from its body (`body`: body indices)."""
    density = np.array([b.initial_density or 0.0 for b in scene.bodies])[body]
    pressure = np.array([b.initial_pressure or 0.0 for b in scene.bodies])[body]
    return density, pressure


def _initial_internal_energy(config: IdealGas, scene, body: np.ndarray) -> np.ndarray:
    """e = p / ((gamma - 1) rho)."""
    density, pressure = body_state(scene, body)
    return pressure / ((config.gamma - 1.0) * density)


MATERIAL = MaterialType(
    schema=IdealGas,
    solver_class="solver.materials.kernels.ideal_gas:IdealGas",
    # the specific internal energy e: the gas's state besides the particle's volume
    state=(StateVariable("internal_energy", output=True, initial=_initial_internal_energy),),
)
