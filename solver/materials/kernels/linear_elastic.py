"""Hypoelastic linear elasticity (review B.1, eq. B.5).

sigma <- sigma + lambda tr(de) I + 2 mu de, with de = sym(L) dt. 2D is plane
strain (de_zz = 0 but sigma_zz evolves), 1D is uniaxial strain. The stored energy
is sigma : C^-1 : sigma / 2, exact for this model without keeping the strain.
"""
from __future__ import annotations

import numpy as np
from solver.jit import njit, prange

from solver.kernels import axes
from solver.materials.kernels.elastic import IsotropicElastic


@njit(cache=True, inline="always")
def _update_one(L, stress, p, dt, lam, mu, dim):
    tr = 0.0
    for a in range(dim):
        tr += L[p, a, a]
    tr *= dt
    for a in range(3):
        stress[p, a, a] += lam * tr
    for a in range(dim):
        for b in range(dim):
            stress[p, a, b] += mu * dt * (L[p, a, b] + L[p, b, a])


@njit(parallel=True, cache=True)
def _update(dims, L, stress, dt, lam, mu):
    for p in prange(L.shape[0]):
        _update_one(L, stress, p, dt, lam, mu, len(dims))   # (solver/kernels.py `axes`)


@njit(cache=True)
def _energy(stress, volume, lam, mu, out):
    c = lam / (3.0 * lam + 2.0 * mu)
    for p in range(stress.shape[0]):
        ss = 0.0
        tr = 0.0
        for a in range(3):
            tr += stress[p, a, a]
            for b in range(3):
                ss += stress[p, a, b] * stress[p, a, b]
        out[p] = volume[p] * (ss - c * tr * tr) / (4.0 * mu)


class LinearElastic(IsotropicElastic):
    def update_stress(self, particles, sl: slice, dt: float) -> None:
        _update(axes(particles.L.shape[1]), particles.L[sl], particles.stress[sl], dt, self.lam, self.mu)

    def stress_update_lines(self, dim: int) -> tuple[str, ...]:
        """This update as the fused G2P runs it, right after it forms L_p (solver/fused_template.py
        `_stress_update`: l{a}{b} are L_p's entries, q0 and q1 lambda and mu): `_update_one`'s
        operations in its order, so the same bits as `update_stress` with MPM_FMA=0 (to
        round-off with FMA contraction, the default: solver/fused_template.py CONTRACT)."""
        trace = " + ".join(["0.0"] + [f"l{a}{a}" for a in range(dim)])
        return (f"le_tr = ({trace}) * dt",
                *[f"stress[p, {a}, {a}] += q0 * le_tr" for a in range(3)],
                *[f"stress[p, {a}, {b}] += q1 * dt * (l{a}{b} + l{b}{a})" for a in range(dim) for b in range(dim)])

    def particle_strain_energy(self, particles, sl: slice) -> np.ndarray:
        out = np.empty(sl.stop - sl.start)
        _energy(particles.stress[sl], particles.volume[sl], self.lam, self.mu, out)
        return out
