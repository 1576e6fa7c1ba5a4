"""The `modified_cam_clay` material: Modified Cam-Clay (Roscoe & Burland 1968) for clay,
in effective stress (compression positive in the formulas: p' = -tr(sigma')/3, q =
sqrt(3/2 s:s); the solver's stress stays tension positive):

    f = q^2 / M^2 + p' (p' - p_c) <= 0          (the yield ellipse; M = critical_state_slope)
    K = (1 + e) p' / kappa,  G = 3 K (1 - 2 nu) / (2 (1 + nu))      (pressure-dependent elasticity)
    dp_c = p_c (1 + e) / (lambda - kappa) d eps_v^p                 (hardening, associated flow)

with e the current void ratio, (1 + e) = (1 + initial_void_ratio) V / V0. The return
mapping is implicit (backward Euler, closest point: solver/materials/kernels/modified_cam_clay.py).

The model has no stiffness at p' = 0, so a body of it needs an initial stress (the body's
`initial_stress`, geostatic): validation asks for one. Where p' is below
`minimum_pressure` (near a free surface, in tension) the stiffness is that at the minimum.
Where the initial stress lies outside the ellipse of `preconsolidation_pressure`, p_c
starts at the ellipse through it (normally consolidated there).

The stress it updates is the effective stress: with a `pore_fluid` (solver/pore_fluid.py)
the pore pressure is a particle field of its own and the total stress sigma' - p I.
"""

import math
from typing import Annotated, Any, Literal

import numpy as np
from pydantic import Field, Strict, model_serializer, model_validator

from solver.initial_stress import vertical_axis
from solver.materials.drucker_prager import FRICTIONAL_STATE
from solver.materials.registry import MaterialType, StateVariable
from solver.schema import BaseMaterial, Positive, fmt, problems_at

PRECONSOLIDATION = "preconsolidation_pressure"
# the model's strain energy: V sigma' : d eps^e summed over the steps (kernels/modified_cam_clay.py)
ELASTIC_WORK = "elastic_work"
MINIMUM_PRESSURE_FRACTION = 0.01   # of preconsolidation_pressure: the default minimum_pressure


def _initial_preconsolidation(config, scene, body_index):
    return np.full(body_index.shape[0], config.preconsolidation_pressure)


class ModifiedCamClay(BaseMaterial):
    model: Literal["modified_cam_clay"]
    density: Positive
    poisson_ratio: Annotated[float, Strict(), Field(ge=0, lt=0.5)]
    lambda_: Positive = Field(alias="lambda")      # slope of the normal compression line in e - ln p'
    kappa: Positive                                # slope of the swelling lines
    critical_state_slope: Positive                 # M, q = M p' at the critical state
    preconsolidation_pressure: Positive            # p_c at the start (Pa)
    initial_void_ratio: Positive                   # e0
    minimum_pressure: Positive | None = None       # p' floor of the stiffness; None: 1 % of p_c

    @model_serializer(mode="wrap")
    def _named_lambda(self, handler):
        """Dumped as the scene names it ("lambda"), by alias or not: the service stores
        scenes with model_dump_json() and loads them again."""
        data = handler(self)
        if isinstance(data, dict) and "lambda_" in data:
            data["lambda"] = data.pop("lambda_")
        return data

    @model_validator(mode="after")
    def _slopes(self) -> "ModifiedCamClay":
        if self.kappa >= self.lambda_:
            raise problems_at([("kappa", f"must be < lambda ({fmt(self.lambda_)}): the swelling line is "
                                         "flatter than the normal compression line")])
        return self

    @property
    def floor_pressure(self) -> float:
        if self.minimum_pressure is not None:
            return self.minimum_pressure
        return MINIMUM_PRESSURE_FRACTION * self.preconsolidation_pressure

    def shear_to_bulk(self) -> float:
        """G / K from Poisson's ratio."""
        nu = self.poisson_ratio
        return 3.0 * (1.0 - 2.0 * nu) / (2.0 * (1.0 + nu))

    def wave_speed_at(self, pressure: float, void_ratio: float) -> float:
        """sqrt((K + 4 G / 3) / rho) at mean effective stress `pressure` (floored)."""
        bulk = (1.0 + void_ratio) * max(pressure, self.floor_pressure) / self.kappa
        return math.sqrt(bulk * (1.0 + 4.0 * self.shear_to_bulk() / 3.0) / self.density)

    def dilatational_wave_speed(self) -> float:
        """At p' = preconsolidation_pressure, where the scene is not known (the stability limit
        uses `initial_wave_speed_in`; runs follow the current stiffness)."""
        return self.wave_speed_at(self.preconsolidation_pressure, self.initial_void_ratio)

    def initial_wave_speed_in(self, scene: Any, body: Any) -> float:
        """At the largest p' of the body's geostatic stress, p' = (1 + 2 k0) / 3 rho g d with its
        box's height as the depth d (solver/initial_stress.py): what the run starts from."""
        if body.initial_stress is None or not any(scene.gravity or ()):
            return self.dilatational_wave_speed()
        axis, _ = vertical_axis(scene.gravity)
        lower, upper = body.geometry.shape().bounding_box()
        k0 = body.initial_stress.k0 if body.initial_stress.k0 is not None else self.default_k0()
        sigma_v = self.density * abs(float(scene.gravity[axis])) * float(upper[axis] - lower[axis])
        return self.wave_speed_at((1.0 + 2.0 * k0) / 3.0 * sigma_v, self.initial_void_ratio)

    def default_k0(self) -> float:
        """Jaky's 1 - sin(phi_cs), with sin(phi_cs) = 3 M / (6 + M) (triaxial compression)."""
        m = self.critical_state_slope
        return 1.0 - min(3.0 * m / (6.0 + m), 1.0)

    def body_problems(self, path: str, body: Any) -> list[tuple[str, str]]:
        if body.initial_stress is None:
            return [(f"{path}.initial_stress", "required for a 'modified_cam_clay' material: its stiffness "
                                               "K = (1 + e) p' / kappa vanishes in a stress-free body "
                                               "(give {\"type\": \"geostatic\"})")]
        return []


MATERIAL = MaterialType(
    schema=ModifiedCamClay,
    solver_class="solver.materials.kernels.modified_cam_clay:ModifiedCamClay",
    state=(*FRICTIONAL_STATE,
           StateVariable(PRECONSOLIDATION, output=True, initial=_initial_preconsolidation),
           StateVariable(ELASTIC_WORK)),
)
