"""The `linear_elastic` material: hypoelastic linear elasticity (review B.1; the
stress update is solver/materials/kernels/linear_elastic.py)."""

from typing import Literal

from solver.materials.registry import MaterialType
from solver.schema import ElasticMaterial


class LinearElastic(ElasticMaterial):
    model: Literal["linear_elastic"]


MATERIAL = MaterialType(schema=LinearElastic, solver_class="solver.materials.kernels.linear_elastic:LinearElastic")
