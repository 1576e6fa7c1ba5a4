"""The `mohr_coulomb` material: perfectly plastic Mohr-Coulomb with a non-associated flow
rule, returned in principal stresses to a plane, an edge or the apex (de Souza Neto,
Peric & Owen 2008, sec. 8.2.2, Boxes 8.4-8.5; Clausen, Damkilde & Andersen 2006); the
return mapping is solver/materials/kernels/mohr_coulomb.py. With friction_angle 0 it is
Tresca (undrained clay, cohesion = c_u)."""

from typing import Literal

from solver.materials.drucker_prager import FRICTIONAL_STATE, FrictionalMaterial
from solver.materials.registry import MaterialType


class MohrCoulomb(FrictionalMaterial):
    model: Literal["mohr_coulomb"]


MATERIAL = MaterialType(
    schema=MohrCoulomb,
    solver_class="solver.materials.kernels.mohr_coulomb:MohrCoulomb",
    state=FRICTIONAL_STATE,
)
