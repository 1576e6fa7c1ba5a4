"""The `j2_plasticity` material: small-strain J2 plasticity with linear isotropic
hardening (review C.4; the return mapping is solver/materials/kernels/j2_plasticity.py)."""

from typing import Literal

from solver.materials import plastic_work
from solver.materials.registry import MaterialType, StateVariable
from solver.schema import ElasticMaterial, NonNegative, Positive


class J2Plasticity(ElasticMaterial):
    model: Literal["j2_plasticity"]
    yield_stress: Positive
    hardening_modulus: NonNegative = 0.0  # 0: perfectly plastic


MATERIAL = MaterialType(
    schema=J2Plasticity,
    solver_class="solver.materials.kernels.j2_plasticity:J2Plasticity",
    state=(StateVariable("plastic_strain", output=True),   # equivalent plastic strain
           plastic_work.STATE),
)
