"""The `neo_hookean` material: compressible neo-Hookean hyperelasticity (review
B.2; the stress update is solver/materials/kernels/neo_hookean.py)."""

from typing import Literal

from solver.materials.registry import MaterialType
from solver.schema import ElasticMaterial


class NeoHookean(ElasticMaterial):
    model: Literal["neo_hookean"]


MATERIAL = MaterialType(schema=NeoHookean, solver_class="solver.materials.kernels.neo_hookean:NeoHookean")
