"""The `johnson_cook` material: hypoelastic-plastic Johnson-Cook flow stress with an
equation of state, damage, failure and adiabatic heating (Karamelo 2.4.2, review
B.3; the update is solver/materials/kernels/johnson_cook.py with kernels/eos.py
and kernels/damage.py)."""

import math
from typing import Annotated, Any, Literal, Union

import numpy as np
from pydantic import Field, Strict, ValidationInfo, field_validator, model_validator

from solver.materials import plastic_work
from solver.materials.registry import MaterialType, StateVariable
from solver.schema import ElasticMaterial, NonNegative, Positive, Real, SceneModel, fmt, problems_at, scene_error


class LinearEOS(SceneModel):
    model: Literal["linear"]


class MieGruneisenEOS(SceneModel):
    model: Literal["mie_gruneisen"]
    c0: Positive  # bulk speed of sound
    s: NonNegative  # slope of the linear Hugoniot
    gamma0: NonNegative  # Grüneisen gamma of the reference state


class JohnsonCookDamage(SceneModel):
    model: Literal["johnson_cook"]
    D1: Real
    D2: Real
    D3: Real
    D4: Real
    D5: Real
    evolution_factor: Positive = 10.0  # D = k (D_init - 1): 10 in [K] eq. 2.16, 1 in [R] Alg. 13


class Failure(SceneModel):
    """MPM3DMP 5.3: a particle fails when either criterion given is met."""

    plastic_strain: Positive | None = None  # equivalent plastic strain at failure
    min_pressure: Annotated[float, Strict(), Field(lt=0)] | None = None  # failure pressure (a tension, < 0)


class JohnsonCook(ElasticMaterial):
    model: Literal["johnson_cook"]
    A: Positive
    B: NonNegative
    n: NonNegative
    C: NonNegative
    reference_strain_rate: Positive
    # thermal softening exponent: only used where a temperature can leave room_temperature
    # (heating, or a body's initial_temperature); _thermal_keys_with_heating and
    # temperature_problems ask for it there
    m: Positive | None = None
    room_temperature: NonNegative
    melt_temperature: Positive
    specific_heat: Positive | None = None   # only used with heating (taylor_quinney > 0)
    taylor_quinney: Annotated[float, Strict(), Field(ge=0, le=1)]
    eos: Annotated[Union[LinearEOS, MieGruneisenEOS], Field(discriminator="model")] = LinearEOS(model="linear")
    damage: JohnsonCookDamage | None = None
    failure: Failure | None = None

    def dilatational_wave_speed(self) -> float:
        """sqrt((K + 4/3 G) / rho) with the EOS bulk modulus (rho0 c0^2 for Mie-Gruneisen)."""
        bulk = self.density * self.eos.c0**2 if self.eos.model == "mie_gruneisen" else self.bulk_modulus
        return math.sqrt((bulk + 4 * self.shear_modulus / 3) / self.density)

    @property
    def heats(self) -> bool:
        return self.taylor_quinney > 0

    def temperature_problems(self, path: str, body: Any) -> list[tuple[str, str]]:
        start = body.initial_temperature
        if self.m is None and start is not None and start != self.room_temperature:
            return [(f"materials.{body.material}.m", f"required: {path} starts at initial_temperature = "
                                                     f"{fmt(start)}, not room_temperature, "
                                                     "so the thermal softening exponent is used")]
        return []

    @model_validator(mode="after")
    def _thermal_keys_with_heating(self) -> "JohnsonCook":
        if not self.heats:
            return self
        heating = f"required with heating (taylor_quinney = {fmt(self.taylor_quinney)} > 0; 0 makes it isothermal)"
        missing = [(key, heating) for key in ("m", "specific_heat") if getattr(self, key) is None]
        if missing:
            raise problems_at(missing)
        return self

    @field_validator("melt_temperature")
    @classmethod
    def _melt_above_room(cls, value: float, info: ValidationInfo) -> float:
        room = info.data.get("room_temperature")
        if room is not None and not value > room:
            raise scene_error(f"must be > room_temperature = {fmt(room)}")
        return value


def _initial_temperature(config: JohnsonCook, scene, body: np.ndarray) -> np.ndarray:
    """The body's initial_temperature, else the material's room temperature."""
    per_body = [config.room_temperature if b.initial_temperature is None else b.initial_temperature
                for b in scene.bodies]
    return np.array(per_body, dtype=np.float64)[body]


def _tracks_damage(config: JohnsonCook) -> bool:
    return config.damage is not None or config.failure is not None


MATERIAL = MaterialType(
    schema=JohnsonCook,
    solver_class="solver.materials.kernels.johnson_cook:JohnsonCook",
    state=(
        StateVariable("plastic_strain", output=True),
        StateVariable("plastic_strain_rate"),    # the last step's, the guess of the rate-dependent return
        plastic_work.STATE,
        # NaN where no model tracks a temperature
        StateVariable("temperature", fill=math.nan, output=True, initial=_initial_temperature),
        StateVariable("damage", output=True, when=_tracks_damage),   # 1: failed
        StateVariable("damage_init", when=lambda config: config.damage is not None),   # D_init of the damage model
    ),
)
