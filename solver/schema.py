"""The building blocks of the scene's pydantic models, shared by solver/scene.py
and the material declarations (solver/materials/<name>.py).

They live here, below both, because the scene's `materials` union is built from
the material registry: a material module cannot import solver.scene (it would
import itself through the union), and scene.py imports the materials. Like the
scene, this module loads without numba.
"""

import math
from typing import Annotated, Any, ClassVar

from pydantic import BaseModel, ConfigDict, Field, Strict, field_validator
from pydantic_core import PydanticCustomError

from solver import capabilities

Real = Annotated[float, Strict()]  # ints are accepted, booleans and strings are not
Boolean = Annotated[bool, Strict()]
Positive = Annotated[float, Strict(), Field(gt=0)]
NonNegative = Annotated[float, Strict(), Field(ge=0)]


def scene_error(message: str) -> PydanticCustomError:
    """One problem, at the path of the value being validated."""
    # "{detail}" keeps braces inside the message (e.g. quoted user text) literal.
    return PydanticCustomError("scene_error", "{detail}", {"detail": message})


def problems_at(problems: list[tuple[str, str]]) -> PydanticCustomError:
    """Several problems at paths relative to the model that raises them."""
    detail = "; ".join(f"{path}: {message}" if path else message for path, message in problems)
    return PydanticCustomError("scene_problems", "{detail}", {"detail": detail, "problems": problems})


def require_supported(value: Any, capability: str) -> Any:
    """`value` if the solver implements it (the set `capability` of solver.capabilities,
    read now so that tests and later registrations see the current one)."""
    if value not in getattr(capabilities, capability):
        raise scene_error(f"{value!r} is not supported yet")
    return value


def supported(field: str, capability: str):
    """A validator of `field` (declare it in the model's body) that refuses a value the solver
    does not implement yet: require_supported(value, capability)."""
    return field_validator(field)(classmethod(lambda cls, value: require_supported(value, capability)))


def fmt(value: float) -> str:
    return f"{value:g}"


class SceneModel(BaseModel):
    # Every model of the scene: unknown keys are errors, NaN and infinity too.
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class PoreFluid(SceneModel):
    """The water filling a saturated soil's pores (solver/pore_fluid.py): with it the material's
    stress model works on the effective stress and the pore pressure is a field of its own."""

    bulk_modulus: Positive              # K_w, Pa
    density: Positive                   # rho_w, kg/m^3
    hydraulic_conductivity: Positive    # k, m/s (Darcy's, for water under g_n = 9.81 m/s^2)
    porosity: Annotated[float, Strict(), Field(gt=0, lt=1)]   # n

    @property
    def storage_modulus(self) -> float:
        """K_w / n: the pore pressure's stiffness against the skeleton's volume change."""
        return self.bulk_modulus / self.porosity


class BaseMaterial(SceneModel):
    """A material entry of the scene. A subclass declares ``model: Literal["<name>"]``,
    its keys, and the wave speed the time step estimate starts from.

    Every material may carry the thermal keys (solver/thermal.py): conduction runs in
    a material with thermal_conductivity > 0 (it needs specific_heat), and
    thermal_expansion (1/K, linear) strains the solid models ([R] 5.26). Absent, a
    scene allocates and runs nothing thermal."""

    thermal_conductivity: NonNegative | None = None   # k, W/(m K); None or 0: no conduction in it
    specific_heat: Positive | None = None              # c, J/(kg K)
    thermal_expansion: Real | None = None              # alpha, 1/K; None or 0: no thermal strain
    # method keys this material sets where the scene leaves them out (Scene._material_method_defaults)
    method_defaults: ClassVar[dict[str, Any]] = {}
    # What the scene's checks (solver/scene.py) ask of a material, declared by the material so
    # that the scene imports no material class. rigid: its bodies follow their prescribed
    # velocity (solver/rigid.py) and have no stress of their own.
    rigid: ClassVar[bool] = False
    # The body keys that give its bodies their initial state (a gas's density and pressure):
    # required on its bodies, refused on the bodies of every other material.
    body_state_keys: ClassVar[tuple[str, ...]] = ()
    pore_fluid: PoreFluid | None = None                # saturated soil (solid skeletons only)

    @field_validator("model", check_fields=False)
    @classmethod
    def _model_supported(cls, value: str) -> str:
        return require_supported(value, "MATERIAL_MODELS")

    def dilatational_wave_speed(self) -> float | None:
        """Speed of the fastest wave, for the adaptive time step; None when the
        material alone does not determine it."""
        return None

    def initial_wave_speed(self, body: Any) -> float:
        """The wave speed in `body` (made of this material) at t = 0, for the summary's
        time step estimate; 0 where no wave travels."""
        return self.dilatational_wave_speed() or 0.0

    def body_problems(self, path: str, body: Any) -> list[tuple[str, str]]:
        """What a body made of this material lacks (path: the body's, "bodies[i]")."""
        return []

    def scene_problems(self, path: str, scene: Any) -> list[tuple[str, str]]:
        """What the rest of the scene lacks for this material's own options (path: the
        material's, "materials.<name>")."""
        return []

    def temperature_problems(self, path: str, body: Any) -> list[tuple[str, str]]:
        """What this material lacks for a body of it to start at the body's initial_temperature
        (checked after the body's state keys)."""
        return []

    @property
    def conducts(self) -> bool:
        return bool(self.thermal_conductivity)


class ElasticMaterial(BaseMaterial):
    """Isotropic elastic constants shared by the solid models."""

    density: Positive
    youngs_modulus: Positive
    poisson_ratio: Annotated[float, Strict(), Field(ge=0, lt=0.5)]

    def lame_parameters(self) -> tuple[float, float]:
        """(lambda, mu) from Young's modulus and Poisson's ratio."""
        e, nu = self.youngs_modulus, self.poisson_ratio
        return e * nu / ((1 + nu) * (1 - 2 * nu)), e / (2 * (1 + nu))

    @property
    def bulk_modulus(self) -> float:
        return self.youngs_modulus / (3 * (1 - 2 * self.poisson_ratio))

    @property
    def shear_modulus(self) -> float:
        return self.lame_parameters()[1]

    def dilatational_wave_speed(self) -> float:
        """sqrt((lambda + 2 mu) / rho)."""
        lam, mu = self.lame_parameters()
        return math.sqrt((lam + 2 * mu) / self.density)


# Variables allowed in expressions; X, Y, Z are reference (initial) coordinates.
SPACE_VARIABLES = ("x", "y", "z")
TIME_VARIABLES = ("t",)
BODY_FORCE_VARIABLES = ("x", "y", "z", "X", "Y", "Z", "t")
AXIS_OF_VARIABLE = {"x": 0, "y": 1, "z": 2, "X": 0, "Y": 1, "Z": 2}
# output.frames when the scene leaves it out; a scene may always ask for this many
DEFAULT_FRAMES = 51


# Counts (cells, steps, frames) derived from a scene's floats: past this they are "more than
# anything a limit allows", so an absurd ratio (1e308 / 1e-308, or an infinite extent) stays
# a Python int that the limits compare, never an OverflowError in math.ceil / math.floor.
MAX_COUNT = 2**62


def count_up(value: float) -> int:
    """ceil(value) for a count, at most MAX_COUNT (infinite or NaN counts as MAX_COUNT)."""
    return math.ceil(value) if value < MAX_COUNT else MAX_COUNT   # NaN < x is False: MAX_COUNT


def count_down(value: float) -> int:
    """floor(value) for a cell index, clamped to [-MAX_COUNT, MAX_COUNT]."""
    if not value > -MAX_COUNT:   # -inf and NaN
        return -MAX_COUNT
    return math.floor(value) if value < MAX_COUNT else MAX_COUNT
