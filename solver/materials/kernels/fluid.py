"""Weakly compressible Newtonian fluid ([K] eq. 2.17-2.18, [R] eq. 5.30-5.31).

sigma = 2 mu_N dev(D) - p I, D = sym(L) (padded to 3x3: plane strain has D_zz = 0,
1D uniaxial strain D_yy = D_zz = 0, so the deviator has a zz (and yy) part and
tr(sigma) = -3 p exactly). The Tait equation of state gives the pressure from the
density, and the density from J: rho = rho0 / J with J = V / V0, so nothing but
the kinematics the step already keeps is needed.

Sound speed: c^2 = dp/drho = K gamma / rho0 (rho / rho0)^(gamma - 1), sqrt(K gamma
/ rho0) at rest. Compressed water is stiffer, so the time step follows the largest
c over the particles of the last update.

Stored energy (for the energy balance): the work done compressing the fluid,
per reference volume W(J) = -int_1^J p dJ' = K [(J^(1 - gamma) - 1) / (gamma - 1)
+ J - 1], which is K gamma (J - 1)^2 / 2 for small strains. The tension cut-off
clips p but not this energy: with the cut-off active it is an upper estimate.
"""
from __future__ import annotations

import math

import numpy as np
from solver.jit import njit, prange

from solver.kernels import axes, flag, rows_equal


@njit(cache=True, inline="always")
def _update_one(L, volume, volume0, stress, p, rho0, K, gamma, mu, min_pressure, dim, linear):
    """Stress of particle p; returns its squared sound speed. `linear` (a constant at each
    call): gamma is 1, and (rho / rho0)^1 is rho / rho0 exactly, without pow()."""
    ratio = volume0[p] / volume[p]                  # rho / rho0 = 1 / J
    stiff = ratio if linear else ratio**gamma
    pressure = max(K * (stiff - 1.0), min_pressure)
    tr = 0.0
    for a in range(dim):
        tr += L[p, a, a]
    for a in range(3):
        for b in range(3):
            d = 0.5 * (L[p, a, b] + L[p, b, a]) if a < dim and b < dim else 0.0
            if a == b:
                d -= tr / 3.0
                stress[p, a, b] = 2.0 * mu * d - pressure
            else:
                stress[p, a, b] = 2.0 * mu * d
    return K * gamma * stiff / (ratio * rho0)


@njit(parallel=True, cache=True)
def _update(dims, linear, L, volume, volume0, stress, rho0, K, gamma, mu, min_pressure):
    """Stress of every particle; returns the largest sound speed. `dims` and `linear`
    (solver/kernels.py `axes`, `flag(gamma == 1)`) are compile-time constants: pow() was 21
    of the 27 ns a particle of mpm88's stress update (gamma = 1), and a runtime test of gamma
    inside the loop did not remove it (LLVM may evaluate pow before the select)."""
    c2_max = 0.0   # (a max reduction over threads)
    for p in prange(L.shape[0]):
        c2_max = max(c2_max, _update_one(L, volume, volume0, stress, p, rho0, K, gamma, mu, min_pressure, len(dims),
                                         linear.ndim == 2))
    return math.sqrt(c2_max)


@njit(cache=True)
def _energy(volume, volume0, K, gamma, out):
    for p in range(volume.shape[0]):
        J = volume[p] / volume0[p]
        # (J^(1-gamma) - 1) / (gamma - 1) tends to -ln J as gamma -> 1
        w = -math.log(J) if gamma == 1.0 else (J ** (1.0 - gamma) - 1.0) / (gamma - 1.0)
        out[p] = volume0[p] * K * (w + J - 1.0)


class Fluid:
    def __init__(self, config, dimension: int):
        self.density = config.density
        self.K, self.gamma, self.mu = config.bulk_modulus, config.gamma, config.viscosity
        self.min_pressure = -config.tension_cutoff if config.tension_cutoff is not None else -math.inf
        self.wave_speed = config.dilatational_wave_speed()

    stress_sets_wave_speed = True   # (a stress update put off leaves the last one's: solver/step/fused.py)

    def update_stress(self, particles, sl: slice, dt: float) -> None:
        L = particles.L   # (n, 3, 3) in an axisymmetric run: its hoop rate too
        self.wave_speed = _update(axes(L.shape[1]), flag(self.gamma == 1.0), L[sl], particles.volume[sl],
                                  particles.volume0[sl], particles.stress[sl], self.density, self.K, self.gamma,
                                  self.mu, self.min_pressure)

    def stress_lines(self, dim: int) -> tuple[str, ...]:
        """The in-plane stress as the fused P2G forms it from L_p and V0_p / V_p (solver/fused_template.py
        `_stress_of_particle`; q0..q3 are K, mu, the pressure floor and gamma): `_update_one`'s
        operations in its order, so the same bits as the stored stress with MPM_FMA=0 (to
        round-off with FMA contraction, the default: solver/fused_template.py CONTRACT). gamma = 1 is
        written in."""
        lines = ["fl_ratio = vol0_p / vol_p",
                 "fl_stiff = fl_ratio" if self.gamma == 1.0 else "fl_stiff = fl_ratio**q3",
                 "fl_pressure = max(q0 * (fl_stiff - 1.0), q2)",
                 "fl_tr = " + " + ".join(["0.0"] + [f"l{a}{a}" for a in range(dim)])]
        for a in range(dim):
            for b in range(dim):
                d = f"0.5 * (l{a}{b} + l{b}{a})"
                lines.append(f"sig{a}{b} = 2.0 * q1 * ({d} - fl_tr / 3.0) - fl_pressure" if a == b
                             else f"sig{a}{b} = 2.0 * q1 * ({d})")
        return tuple(lines)

    def stress_free(self, F, L, volume, volume0) -> bool:
        """Whether `stress_lines` give exactly zero at every particle (what P2G reads: F_p, L_p,
        V_p, V0_p): where V_p = V0_p, (V0 / V)^gamma = 1, so the pressure is zero unless the floor
        is above it, and L_p = 0, the deviator too."""
        return self.min_pressure <= 0.0 and np.array_equal(volume, volume0) and rows_equal(L, 0.0)

    def stress_parameters(self) -> np.ndarray:
        """q0..q3 of `stress_lines`."""
        return np.array([self.K, self.mu, self.min_pressure, self.gamma])

    def particle_strain_energy(self, particles, sl: slice) -> np.ndarray:
        out = np.empty(sl.stop - sl.start)
        _energy(particles.volume[sl], particles.volume0[sl], self.K, self.gamma, out)
        return out

    def strain_energy(self, particles, sl: slice) -> float:
        return float(self.particle_strain_energy(particles, sl).sum())
