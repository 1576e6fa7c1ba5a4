"""Isotropic elastic constants shared by the elastic models."""
from __future__ import annotations


class IsotropicElastic:
    """Lame parameters and the dilatational wave speed sqrt((lambda + 2 mu) / rho) (review eq. 2.71),
    as the scene entry (solver.schema.ElasticMaterial) computes them."""

    def __init__(self, config, dimension: int):
        self.lam, self.mu = config.lame_parameters()
        self.density = config.density
        self.dimension = dimension
        self.wave_speed = config.dilatational_wave_speed()

    def strain_energy(self, particles, sl: slice) -> float:
        return float(self.particle_strain_energy(particles, sl).sum())
