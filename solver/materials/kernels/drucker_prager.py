"""Perfectly plastic Drucker-Prager with non-associated flow and a tension cut-off
(de Souza Neto, Peric & Owen 2008, "Computational Methods for Plasticity", sec. 8.3.3,
Box 8.8, without hardening). Tension is positive here; m = tr(sigma)/3.

    Phi = sqrt(J2(s)) + eta m - xi c          (yield function)
    Psi = sqrt(J2(s)) + eta_bar m             (plastic potential; eta_bar from psi)

Trial stress by the Jaumann rate (kernels/objective.py), as the other plastic models.
If Phi_trial > 0:
  cone:  dg = Phi_trial / (G + K eta eta_bar),  sqrt(J2) = sqrt(J2_trial) - G dg,
         m = m_trial - K eta_bar dg                  (valid while sqrt(J2) >= 0)
  apex:  otherwise s = 0, m = xi c / eta             (the apex, c cot(phi) for every fit)
Tension cut-off m <= T (T below the apex): where the cone return does not apply
(it ends above T or beyond the apex) or only the cut-off is violated, the return
is to the cut-off, m = T with the trial deviator (associated volumetric flow), or to
its corner with the cone, m = T and sqrt(J2) = xi c - eta T, when the cone does not
hold at m = T with the trial deviator. Every return is radial in the deviatoric plane, so the
equivalent plastic strain grows by (sqrt(J2_trial) - sqrt(J2)) / (sqrt(3) G), and the
plastic work (`plastic_work`) by V sigma : C^-1 : (sigma_trial - sigma).
"""
from __future__ import annotations

import math

import numba
from solver.jit import njit, prange

from solver.materials.drucker_prager import APEX, ELASTIC, SURFACE, TENSION
from solver.materials.kernels import objective
from solver.materials.kernels.frictional import Frictional
from solver.threads import block_bounds


@njit(parallel=True, cache=True)
def _update(L, stress, eps_p, state, volume, work, dt, K, G, eta, eta_bar, xi_c, cutoff, threads):
    bounds = block_bounds(L.shape[0], threads)
    for t in prange(threads):
        _update_block(bounds[t], bounds[t + 1], L, stress, eps_p, state, volume, work, dt, K, G, eta, eta_bar,
                      xi_c, cutoff)


@njit(cache=True)
def _update_block(lo, hi, L, stress, eps_p, state, volume, work, dt, K, G, eta, eta_bar, xi_c, cutoff):
    for p in range(lo, hi):
        # the Jaumann trial stress in nine scalars (kernels/objective.py says why)
        D, w21, w02, w10 = objective.rate_parts(L[p])
        sigma = objective.rotated(stress[p], w21, w02, w10, dt)
        m_trial = -(objective.mean_pressure(sigma) - K * objective.trace(D) * dt)
        s = objective.trial_deviator(sigma, D, 2.0 * G * dt)
        j_trial = objective.von_mises_of(s) / math.sqrt(3.0)     # sqrt(J2)
        m, j, state[p] = return_map(m_trial, j_trial, K, G, eta, eta_bar, xi_c, cutoff)
        if state[p] != ELASTIC:
            eps_p[p] += (j_trial - j) / (math.sqrt(3.0) * G)
            # sigma_{n+1} : C^-1 : (sigma_trial - sigma_{n+1}), the deviator radial (s:s = 2 J2)
            work[p] += volume[p] * (j * (j_trial - j) / G + m * (m_trial - m) / K)
            s = objective.scaled(s, j / j_trial if j_trial > 0.0 else 0.0)
        objective.assemble_from(s, -m, stress[p])


@njit(cache=True)
def return_map(m, j, K, G, eta, eta_bar, xi_c, cutoff):
    """(m, sqrt(J2), yield state) after the return from the trial (m, j)."""
    if j + eta * m - xi_c > 0.0:
        dg = (j + eta * m - xi_c) / (G + K * eta * eta_bar)
        if j - G * dg >= 0.0 and m - K * eta_bar * dg <= cutoff:
            return m - K * eta_bar * dg, j - G * dg, SURFACE
        if cutoff == math.inf:               # beyond the apex (only when eta > 0)
            return xi_c / eta, 0.0, APEX
    elif m <= cutoff:
        return m, j, ELASTIC
    # the cut-off (associated, volumetric): m = T with the trial deviator, or at the
    # corner with the cone when the cone does not hold there
    return cutoff, min(j, xi_c - eta * cutoff), TENSION


class DruckerPrager(Frictional):
    def __init__(self, config, dimension: int):
        super().__init__(config, dimension)
        self.eta, xi, self.eta_bar = config.strength()
        self.xi_c = xi * config.cohesion

    def update_stress(self, particles, sl: slice, dt: float) -> None:
        _update(particles.L[sl], particles.stress[sl], particles.extra["plastic_strain"][sl],
                particles.extra["yield_state"][sl], particles.volume[sl], particles.extra["plastic_work"][sl],
                dt, self.bulk, self.mu, self.eta, self.eta_bar,
                self.xi_c, self.tension_cutoff, numba.get_num_threads())
