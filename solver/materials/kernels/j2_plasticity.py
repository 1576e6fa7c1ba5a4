"""Small-strain J2 plasticity with linear isotropic hardening (review C.4, Simo & Hughes 3.3).

Hypoelastic, objective through the Jaumann rate (solver/materials/objective.py):

    sigma_trial = Q sigma Q^T + lambda tr(de) I + 2 mu de,       de = D dt
    q_trial = sqrt(3/2 s_trial : s_trial),  sigma_y = yield_stress + H eps_p
    if q_trial > sigma_y:   d eps_p = (q_trial - sigma_y) / (3 mu + H)
                            s <- s_trial (sigma_y + H d eps_p) / q_trial

The radial return is exact for proportional (radial) loading with linear
hardening: in uniaxial stress the curve is E up to yield_stress, then
E_t = E H / (E + H). Per particle it keeps the equivalent plastic strain
(`plastic_strain`) and the work of plastic flow (`plastic_work`, J: q d eps_p V, with
q of the returned stress; solver/materials/plastic_work.py). The stored (elastic) energy is sigma : C^-1 : sigma / 2.
"""
from __future__ import annotations

import numba
from solver.jit import njit, prange

from solver.materials.kernels import objective
from solver.materials.kernels.linear_elastic import LinearElastic
from solver.threads import block_bounds


@njit(parallel=True, cache=True)
def _update(L, stress, eps_p, volume, work, dt, K, G, yield_stress, H, threads):
    bounds = block_bounds(L.shape[0], threads)
    for t in prange(threads):
        _update_block(bounds[t], bounds[t + 1], L, stress, eps_p, volume, work, dt, K, G, yield_stress, H)


@njit(cache=True)
def _update_block(lo, hi, L, stress, eps_p, volume, work, dt, K, G, yield_stress, H):
    for p in range(lo, hi):
        # the Jaumann trial stress in nine scalars (kernels/objective.py says why)
        D, w21, w02, w10 = objective.rate_parts(L[p])
        sigma = objective.rotated(stress[p], w21, w02, w10, dt)
        pressure = objective.mean_pressure(sigma) - K * objective.trace(D) * dt
        s = objective.trial_deviator(sigma, D, 2.0 * G * dt)
        q = objective.von_mises_of(s)
        sigma_y = yield_stress + H * eps_p[p]
        if q > sigma_y:
            d_eps = (q - sigma_y) / (3.0 * G + H)
            eps_p[p] += d_eps
            flow = sigma_y + H * d_eps                  # q of the returned stress
            work[p] += volume[p] * flow * d_eps         # sigma_{n+1} : d eps_p (plastic_work.py)
            s = objective.scaled(s, flow / q)
        objective.assemble_from(s, pressure, stress[p])


class J2Plasticity(LinearElastic):
    """Linear elastic inside the yield surface: the stored energy is LinearElastic's."""

    def __init__(self, config, dimension: int):
        super().__init__(config, dimension)
        self.bulk = self.lam + 2.0 * self.mu / 3.0
        self.yield_stress = config.yield_stress
        self.hardening = config.hardening_modulus

    def update_stress(self, particles, sl: slice, dt: float) -> None:
        _update(particles.L[sl], particles.stress[sl], particles.extra["plastic_strain"][sl],
                particles.volume[sl], particles.extra["plastic_work"][sl],
                dt, self.bulk, self.mu, self.yield_stress, self.hardening, numba.get_num_threads())
