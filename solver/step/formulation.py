"""Update- and total-Lagrangian MPM: which positions, volumes and stress measure feed
the same phases (review 2.5 and 2.6, Algorithms 2 and 3).

|                    | ULMPM                                  | TLMPM                                         |
|--------------------|----------------------------------------|-----------------------------------------------|
| weights at         | x_p, every step                        | X_p, once (the stencil never changes)         |
| f_I from           | V_p sigma_p                            | V0_p P_p, with P = J sigma F^-T               |
| kinematics         | L = sum v_I (x) grad phi, F += dt L F  | F_dot = sum v_I (x) grad0 phi, F += dt F_dot, L = F_dot F^-1 |
| APIC's affine field| in x                                   | in X                                          |
| stable step        | cfl h / (c + |v|)                      | that times the smallest principal stretch     |

Both give the materials L, F and V = J V0, so every material works with both.
"""
from __future__ import annotations

import numpy as np

from solver import kernels
from solver.tlmpm import first_piola, smallest_stretch


class UpdatedLagrangian:
    name = "ulmpm"
    reference = False   # weights at x_p, evaluated every step (TLMPM: at X_p, once)
    outside = ("position", "left the grid at {where}")

    def positions(self, particles) -> np.ndarray:
        """Where the weights (and APIC's affine field) are evaluated."""
        return particles.x

    def place_particles(self, particles) -> None:
        """Per-particle work arrays of the formulation (none)."""

    def force_measure(self, sim) -> tuple[np.ndarray, np.ndarray]:
        """The volume and stress whose divergence is the internal force."""
        return sim.particles.volume, sim.particles.stress

    def kinematics(self, sim, v_grid: np.ndarray, dt: float) -> int:
        """L_p, F_p, V_p from the grid velocity; the first inverted particle, or -1."""
        p, s = sim.particles, sim.stencil
        return kernels.update_kinematics(sim.spec, s.idx, s.dw, v_grid, dt, p.L, p.F, p.volume, p.volume0,
                                         sim.threads, kernels.flag(self.reference))

    def hoop_measure(self, sim) -> tuple[np.ndarray, np.ndarray]:
        """The volume and stress of the axisymmetric hoop force (solver/axisymmetric.py):
        V_p and sigma_p, with N_I(x_p) / r_p."""
        p = sim.particles
        return p.volume, p.stress

    def time_step_factor(self, sim) -> float:
        return 1.0


class TotalLagrangian(UpdatedLagrangian):
    name = "tlmpm"
    reference = True
    outside = ("reference position", "lies outside the grid")

    def positions(self, particles) -> np.ndarray:
        return particles.X

    def place_particles(self, particles) -> None:
        self.piola = np.zeros(particles.F.shape)   # (axisymmetric: 3x3, index 2 theta, as F)

    def force_measure(self, sim) -> tuple[np.ndarray, np.ndarray]:
        p = sim.particles
        first_piola(p.F, p.stress, self.piola, sim.threads)   # P = J sigma F^-T
        return p.volume0, self.piola

    def kinematics(self, sim, v_grid: np.ndarray, dt: float) -> int:
        """As ULMPM's; in an axisymmetric scene (F 3x3 in 2D) on the in-plane block of F and L,
        V = det(F_rz) V0, which the hoop hook completes with F_thth (solver/axisymmetric.py):
        F is block diagonal there, so the in-plane L = F_dot F^-1 needs only that block."""
        p, s = sim.particles, sim.stencil
        F, L, dim = p.F, p.L, p.dimension
        if F.shape[1] > dim:
            F, L = F[:, :dim, :dim], L[:, :dim, :dim]
        return kernels.update_kinematics(sim.spec, s.idx, s.dw, v_grid, dt, L, F, p.volume, p.volume0,
                                         sim.threads, kernels.flag(self.reference))

    def hoop_measure(self, sim) -> tuple[np.ndarray, np.ndarray]:
        """V0_p = 2 pi R_p A_p and P_p (its P_thth = J sigma_thth / F_thth), with N_I(X_p) / R_p:
        the P of this step's force_measure."""
        return sim.particles.volume0, self.piola

    def time_step_factor(self, sim) -> float:
        """The smallest principal stretch of any particle (at most 1). The reference cells
        deform with the body: a cell squashed to lambda h is crossed by a wave in lambda h / c,
        so the fixed h of the reference grid overstates the stable step where the body is
        compressed (the impact face of a Taylor bar, flattened to a fifth, went unstable at
        the reference step). Karamelo's TLMPM scales its step the same way."""
        return min(sim.domain.min(smallest_stretch(sim.particles.F)), 1.0)


FORMULATIONS = {f.name: f for f in (UpdatedLagrangian, TotalLagrangian)}
