"""What the frictional models (drucker_prager, mohr_coulomb) share: the elastic
constants and strength of the scene entry, the stored energy (linear elastic inside
the surface) and the constants their kernels take."""
from __future__ import annotations

import math

from solver.materials.kernels.linear_elastic import LinearElastic


class Frictional(LinearElastic):
    """Hypoelastic (Jaumann rate, kernels/objective.py) inside a pressure-dependent yield
    surface; the stored energy is LinearElastic's sigma : C^-1 : sigma / 2."""

    def __init__(self, config, dimension: int):
        super().__init__(config, dimension)
        self.bulk = self.lam + 2.0 * self.mu / 3.0
        self.cohesion = config.cohesion
        self.sin_phi = math.sin(math.radians(config.friction_angle))
        self.sin_psi = math.sin(math.radians(config.dilation_angle))
        # the mean stress cap: the cut-off where it lies below the apex, else none (the apex
        # return already caps the mean stress there)
        cutoff = config.tension_cutoff
        below_apex = cutoff is not None and cutoff < config.apex_mean_stress()
        self.tension_cutoff = cutoff if below_apex else math.inf
