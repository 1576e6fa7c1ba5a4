"""Ideal gas with artificial viscosity ([R] 5.4.2, eq. 5.32-5.35).

sigma = -(p + q) I with p = (gamma - 1) rho e, e the specific internal energy of
each particle (`particles.extra["internal_energy"]`), rho = m / V.

Energy equation (adiabatic, no heat flux): de = -(p + q) dv, dv the change of the
specific volume v = 1 / rho over the step. The review's eq. 5.33-5.34 write it with
the strain rate; here dv comes from the volumes themselves: V_new = det(I + L dt)
V_old exactly (the F update of the step), so dv = 1/rho_new - 1/rho_old. The
pressure is taken at the middle of the step, (p_old + p_new) / 2; p_new depends
on e_new linearly, so the update solves it in closed form:

    e_new = (e_old - (p_old / 2 + q) dv) / (1 + (gamma - 1) rho_new dv / 2).

This is the trapezoidal rule on p dv: an adiabatic compression and re-expansion
returns e to where it started to second order in the step.

Artificial viscosity ([R] eq. 5.35) in compression (D_kk = tr L < 0), with L_e
the smallest cell side and a = sqrt(gamma p / rho) the local sound speed:

    q = rho L_e (c_quadratic L_e D_kk^2 - c_linear a D_kk),

the quadratic von Neumann-Richtmyer term and the linear Landshoff term; q spreads
a shock over a few cells instead of letting it ring. q = 0 in expansion.
"""
from __future__ import annotations

import math

import numba
import numpy as np
from solver.jit import njit, prange

from solver.kernels import determinant
from solver.materials.ideal_gas import body_state
from solver.threads import block_bounds


@njit(parallel=True, cache=True)
def _update(L, mass, volume, energy, stress, dt, gamma, cell, c_quadratic, c_linear, threads):
    """Internal energy and stress of every particle; returns the largest sound speed."""
    n, dim = L.shape[0], L.shape[1]
    bounds = block_bounds(n, threads)
    c2_block = np.zeros(threads)
    for t in prange(threads):
        c2_block[t] = _update_block(bounds[t], bounds[t + 1], L, mass, volume, energy, stress, dt, gamma, cell,
                                    c_quadratic, c_linear)
    return math.sqrt(c2_block.max())


@njit(cache=True)
def _update_block(lo, hi, L, mass, volume, energy, stress, dt, gamma, cell, c_quadratic, c_linear):
    dim = L.shape[1]
    step = np.empty((dim, dim))   # per block, in this serial function: never shared between threads
    c2_max = 0.0
    for p in range(lo, hi):
        tr = 0.0
        for a in range(dim):
            tr += L[p, a, a]
            for b in range(dim):
                step[a, b] = dt * L[p, a, b] + (1.0 if a == b else 0.0)
        rho = mass[p] / volume[p]
        rho_old = rho * determinant(step)                  # V_old = V_new / det(I + L dt)
        p_old = (gamma - 1.0) * rho_old * energy[p]
        q = 0.0
        if tr < 0.0:
            a_old = math.sqrt(gamma * max(p_old, 0.0) / rho_old)
            q = rho * cell * (c_quadratic * cell * tr * tr - c_linear * a_old * tr)
        dv = 1.0 / rho - 1.0 / rho_old
        e = (energy[p] - (0.5 * p_old + q) * dv) / (1.0 + 0.5 * (gamma - 1.0) * rho * dv)
        energy[p] = e
        pressure = (gamma - 1.0) * rho * e
        c2 = gamma * max(pressure, 0.0) / rho
        if c2 > c2_max:
            c2_max = c2
        for a in range(3):
            for b in range(3):
                stress[p, a, b] = -(pressure + q) if a == b else 0.0
    return c2_max


class IdealGas:
    def __init__(self, config, dimension: int):
        self.gamma = config.gamma
        self.c_quadratic = config.artificial_viscosity.quadratic
        self.c_linear = config.artificial_viscosity.linear
        self.cell = 0.0
        self.wave_speed = 0.0

    def init_particles(self, particles, sl: slice, scene) -> None:
        """Initial stress -p I and sound speed from the bodies (the registry has set e;
        the mass is rho V already)."""
        self.cell = min(scene.cell_sizes())
        density, pressure = body_state(scene, particles.body[sl])
        stress = particles.stress[sl]
        stress[:] = 0.0
        for a in range(3):
            stress[:, a, a] = -pressure
        self.wave_speed = float(np.sqrt(self.gamma * pressure / density).max())

    def update_stress(self, particles, sl: slice, dt: float) -> None:
        self.wave_speed = _update(particles.L[sl], particles.mass[sl], particles.volume[sl],
                                  particles.extra["internal_energy"][sl], particles.stress[sl], dt,
                                  self.gamma, self.cell, self.c_quadratic, self.c_linear, numba.get_num_threads())

    def particle_strain_energy(self, particles, sl: slice) -> np.ndarray:
        """The internal energy m e: what the gas stores and gives back as kinetic energy."""
        return particles.mass[sl] * particles.extra["internal_energy"][sl]

    def strain_energy(self, particles, sl: slice) -> float:
        return float(self.particle_strain_energy(particles, sl).sum())
