"""The `fluid` material: a weakly compressible Newtonian fluid with the Tait
equation of state ([K] eq. 2.17-2.18; the stress update is
solver/materials/kernels/fluid.py)."""

import math
from typing import Literal

from solver.materials.registry import MaterialType
from solver.schema import BaseMaterial, NonNegative, Positive


class Fluid(BaseMaterial):
    """Weakly compressible fluid, Tait EOS p = bulk_modulus ((rho/rho0)**gamma - 1)."""

    model: Literal["fluid"]
    density: Positive
    bulk_modulus: Positive
    gamma: Positive = 7.0
    viscosity: NonNegative = 0.0
    # None: the fluid takes any tension; a number: the pressure never falls below
    # -tension_cutoff (0: no tension at all, a free surface cavitates instead).
    tension_cutoff: NonNegative | None = None

    def dilatational_wave_speed(self) -> float:
        """sqrt(bulk_modulus * gamma / density): dp/drho of the Tait EOS at rest."""
        return math.sqrt(self.bulk_modulus * self.gamma / self.density)


MATERIAL = MaterialType(schema=Fluid, solver_class="solver.materials.kernels.fluid:Fluid")
