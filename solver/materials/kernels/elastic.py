"""Isotropic elastic constants shared by the elastic models."""
from __future__ import annotations

import math


class IsotropicElastic:
    """Lame parameters and the dilatational wave speed sqrt((lambda + 2 mu) / rho) (review eq. 2.71)."""

    def __init__(self, config, dimension: int):
        E, nu = config.youngs_modulus, config.poisson_ratio
        self.lam = E * nu / ((1.0 + nu) * (1.0 - 2.0 * nu))
        self.mu = E / (2.0 * (1.0 + nu))
        self.density = config.density
        self.dimension = dimension
        self.wave_speed = math.sqrt((self.lam + 2.0 * self.mu) / self.density)

    def strain_energy(self, particles, sl: slice) -> float:
        return float(self.particle_strain_energy(particles, sl).sum())
