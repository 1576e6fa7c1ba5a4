"""Compressible neo-Hookean hyperelasticity (review B.2, eq. B.6-B.7).

sigma = [mu (F F^T - I) + lambda ln J I] / J, with F padded to 3x3 (plane
strain: F_zz = 1). Stored energy per reference volume:
W = mu/2 (tr C - 3) - mu ln J + lambda/2 (ln J)^2.
"""
from __future__ import annotations

import math

import numpy as np
from solver.jit import njit, prange

from solver.kernels import axes, determinant, rows_equal
from solver.materials.kernels.elastic import IsotropicElastic


@njit(cache=True, inline="always")
def _update_one(F, stress, p, lam, mu, dim):
    J = determinant(F[p])
    c = lam * math.log(J) / J
    for a in range(3):
        for b in range(3):
            bab = 0.0   # (F F^T)_ab of the padded F
            if a < dim and b < dim:
                for k in range(dim):
                    bab += F[p, a, k] * F[p, b, k]
            elif a == b:
                bab = 1.0
            stress[p, a, b] = mu / J * (bab - (1.0 if a == b else 0.0)) + (c if a == b else 0.0)


@njit(parallel=True, cache=True)
def _update(dims, F, stress, lam, mu):
    for p in prange(F.shape[0]):
        _update_one(F, stress, p, lam, mu, len(dims))   # (solver/kernels.py `axes`)


@njit(cache=True)
def _energy(F, volume0, lam, mu, out):
    n, dim = F.shape[0], F.shape[1]
    for p in range(n):
        J = determinant(F[p])
        trC = 3.0 - dim
        for a in range(dim):
            for b in range(dim):
                trC += F[p, a, b] * F[p, a, b]
        lnJ = math.log(J)
        out[p] = volume0[p] * (0.5 * mu * (trC - 3.0) - mu * lnJ + 0.5 * lam * lnJ * lnJ)


class NeoHookean(IsotropicElastic):
    total_stress = True   # sigma(F) each step: the thermal pressure 3 K alpha (T - T0), linearised
    def update_stress(self, particles, sl: slice, dt: float) -> None:
        _update(axes(particles.F.shape[1]), particles.F[sl], particles.stress[sl], self.lam, self.mu)

    def stress_lines(self, dim: int) -> tuple[str, ...]:
        """The in-plane stress as the fused P2G forms it from F_p (solver/fused_template.py
        `_stress_of_particle`: f{a}{b} are F_p's entries, fj its determinant, q0, q1 lambda and
        mu): `_update_one`'s operations in its order, so the same bits as the stored stress with
        MPM_FMA=0 (to round-off with FMA contraction, the default: solver/fused_template.py CONTRACT)."""
        lines = ["nh_c = q0 * math.log(fj) / fj"]
        for a in range(dim):
            for b in range(dim):
                bab = " + ".join(["0.0"] + [f"f{a}{k} * f{b}{k}" for k in range(dim)])
                tail = "- 1.0) + nh_c" if a == b else "- 0.0) + 0.0"
                lines.append(f"sig{a}{b} = q1 / fj * (({bab}) {tail}")
        return tuple(lines)

    def stress_free(self, F, L, volume, volume0) -> bool:
        """Whether `stress_lines` give exactly zero at every particle (what P2G reads: F_p, L_p,
        V_p, V0_p): where F_p = I, J = 1, log J = 0 and F F^T - I = 0, each to the bit."""
        return rows_equal(F, np.eye(F.shape[1]))

    def particle_strain_energy(self, particles, sl: slice) -> np.ndarray:
        out = np.empty(sl.stop - sl.start)
        _energy(particles.F[sl], particles.volume0[sl], self.lam, self.mu, out)
        return out
