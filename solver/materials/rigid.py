"""The `rigid` material: particles that follow their body's prescribed velocity
(solver/rigid.py; its solver object is solver/materials/kernels/rigid.py)."""

from typing import ClassVar, Literal

from solver.materials.registry import MaterialType
from solver.schema import BaseMaterial, Positive


class Rigid(BaseMaterial):
    """Particles follow the body's prescribed ``velocity``; no waves travel in it."""

    model: Literal["rigid"]
    density: Positive
    rigid: ClassVar[bool] = True


MATERIAL = MaterialType(schema=Rigid, solver_class="solver.materials.kernels.rigid:Rigid")
