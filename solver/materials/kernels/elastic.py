"""Isotropic elastic constants shared by the elastic models."""
from __future__ import annotations

import numpy as np


class IsotropicElastic:
    """Lame parameters and the dilatational wave speed sqrt((lambda + 2 mu) / rho) (review eq. 2.71),
    as the scene entry (solver.schema.ElasticMaterial) computes them."""

    # Thermal expansion (solver/thermal.py): the stress of alpha dT I is 3 K alpha dT I. A
    # rate model adds each step's increment; a total one (its stress a function of the
    # current state) has the whole change since the start subtracted after each update.
    total_stress = False

    def __init__(self, config, dimension: int):
        self.lam, self.mu = config.lame_parameters()
        self.density = config.density
        self.dimension = dimension
        self.wave_speed = config.dilatational_wave_speed()

    @property
    def thermal_bulk_modulus(self) -> float:
        return self.lam + 2.0 * self.mu / 3.0

    def stress_parameters(self) -> np.ndarray:
        """q0, q1 of the lines a model gives the fused kernels (`stress_lines` or
        `stress_update_lines`): lambda and mu."""
        return np.array([self.lam, self.mu])

    def strain_energy(self, particles, sl: slice) -> float:
        return float(self.particle_strain_energy(particles, sl).sum())
