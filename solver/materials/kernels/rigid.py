"""The `rigid` material: particles that only carry a prescribed velocity (solver/rigid.py).

It has no stress and stores no energy; no wave travels through it, so it does
not limit the time step (its speed does, through the particles' velocities).
"""
from __future__ import annotations

import numpy as np


class Rigid:
    wave_speed = 0.0

    def __init__(self, config, dimension: int):
        self.density = config.density

    def update_stress(self, particles, sl: slice, dt: float) -> None:
        pass

    def particle_strain_energy(self, particles, sl: slice) -> np.ndarray:
        return np.zeros(sl.stop - sl.start)

    def strain_energy(self, particles, sl: slice) -> float:
        return 0.0
