"""Modified Cam-Clay's stress update (solver/materials/modified_cam_clay.py): an implicit
(backward Euler, closest point) return mapping per particle, in the invariants of the
effective stress, compression positive: p = -tr(sigma)/3, q = sqrt(3/2 s:s).

Elastic predictor over the step, with the void ratio e of the step's start
((1 + e) = (1 + e0) V / V0) and d eps_v = -tr(D) dt (compression positive):

    p_trial = p_n exp((1 + e) d eps_v / kappa)     (dp = K d eps_v^e, K = (1 + e) p / kappa exact)
    s_trial = s_n + 2 G dev(D) dt,  G = K_n (G / K),  K_n at p_n

(the Jaumann rate turns s_n first, kernels/objective.py). Below `minimum_pressure` the
bulk modulus is that at the minimum (the pressure then changes linearly). If
f(p_trial, q_trial, p_c) = q^2/M^2 + p (p - p_c) > 0, the return solves for the plastic
volumetric strain x and the multiplier dg (associated flow, d eps_v^p = dg df/dp,
d eps_q^p = dg df/dq):

    r1 = x - dg (2 p - p_c) = 0,     r2 = q^2 / M^2 + p (p - p_c) = 0,
    p = p_trial exp(-(1 + e) x / kappa),  p_c = p_c,n exp((1 + e) x / (lambda - kappa)),
    q = q_trial / (1 + 6 G dg / M^2)   (s = s_trial q / q_trial: radial in the deviatoric plane)

by Newton on (x, dg) from (0, 0), with backtracking on the residual. Where it does not
converge (not met in the verification), the step is split into 2, 4, ... 64 substeps
with the same return each; past that the particle's yield_state is 2 (UNCONVERGED).
Undrained (d eps_v = 0), kappa ln(p/p_n) + (lambda - kappa) ln(p_c/p_c,n) = 0 holds to
round-off in every step, whatever its size: the closed-form undrained effective stress
path (tests/verification/test_cam_clay.py).

The model is hypoelastic, so its strain energy is not a function of the stress: each
particle adds up the elastic work V sigma' : d eps^e of its steps (`elastic_work`; the
plastic work is that of solver/materials/plastic_work.py), which closes the energy balance.
"""
from __future__ import annotations

import math

import numba
import numpy as np

from solver.jit import njit, prange
from solver.materials.drucker_prager import ELASTIC, SURFACE
from solver.materials.modified_cam_clay import ELASTIC_WORK
from solver.materials.kernels import objective
from solver.threads import block_bounds

ITERATIONS = 60
TOLERANCE = 1e-13      # of r2 / p_scale^2 and of r1 (a strain)
MOST_SUBSTEPS = 64
UNCONVERGED = 2        # the yield state of a return still off the surface after MOST_SUBSTEPS


@njit(cache=True)
def elastic_pressure(p_n, strain, a, p_min):
    """p after the volumetric elastic strain `strain` from p_n, dp = a max(p, p_min) d strain."""
    if p_n >= p_min:
        p = p_n * math.exp(a * strain)
        if p >= p_min:
            return p
        return p_min + a * p_min * (strain - math.log(p_min / p_n) / a)
    p = p_n + a * p_min * strain
    if p <= p_min:
        return p
    return p_min * math.exp(a * (strain - (p_min - p_n) / (a * p_min)))


@njit(cache=True)
def _residuals(x, dg, p_n, strain, q_trial, pc_n, a, b, c, m2, p_min):
    p = elastic_pressure(p_n, strain - x, a, p_min)
    pc = pc_n * math.exp(b * x)
    q = q_trial / (1.0 + c * dg)
    return p, pc, q, x - dg * (2.0 * p - pc), q * q / m2 + p * (p - pc)


@njit(cache=True)
def return_map(p_n, strain, q_trial, pc_n, a, b, c, m2, p_min):
    """(p, q, p_c, x, dg, converged) of the implicit return from the trial state."""
    scale = max(pc_n, abs(p_n), p_min)
    x = dg = 0.0
    p, pc, q, r1, r2 = _residuals(x, dg, p_n, strain, q_trial, pc_n, a, b, c, m2, p_min)
    merit = (a * scale * r1) ** 2 + (r2 / scale) ** 2
    for _ in range(ITERATIONS):
        if abs(r2) <= TOLERANCE * scale * scale and abs(r1) <= TOLERANCE:
            return p, q, pc, x, dg, True
        dp_dx = -a * max(p, p_min)
        dpc_dx = b * pc
        j11, j12 = 1.0 - dg * (2.0 * dp_dx - dpc_dx), -(2.0 * p - pc)
        j21, j22 = (2.0 * p - pc) * dp_dx - p * dpc_dx, -2.0 * c * q * q / (m2 * (1.0 + c * dg))
        det = j11 * j22 - j12 * j21
        if det == 0.0 or not math.isfinite(det):
            break
        step_x, step_g = (r1 * j22 - r2 * j12) / det, (r2 * j11 - r1 * j21) / det
        length = 1.0
        nx, ng = x, dg
        np_, npc, nq, n1, n2, new_merit = p, pc, q, r1, r2, merit
        for _ in range(30):   # backtracking: dg stays >= 0, the residual falls
            nx, ng = x - length * step_x, max(dg - length * step_g, 0.0)
            if abs(b * nx) < 50.0:
                np_, npc, nq, n1, n2 = _residuals(nx, ng, p_n, strain, q_trial, pc_n, a, b, c, m2, p_min)
                new_merit = (a * scale * n1) ** 2 + (n2 / scale) ** 2
                if new_merit < merit:
                    break
            length *= 0.5
        if not new_merit < merit:
            break
        x, dg, p, pc, q, r1, r2, merit = nx, ng, np_, npc, nq, n1, n2, new_merit
    converged = abs(r2) <= TOLERANCE * scale * scale and abs(r1) <= TOLERANCE
    return p, q, pc, x, dg, converged


@njit(cache=True)
def increment(p_n, s_n, pc_n, strain, dev_strain, a, ratio, b, m2, p_min):
    """One backward Euler step from (p_n, s_n, p_c,n) by the volumetric strain `strain`
    (compression positive) and the deviatoric strain `dev_strain` (nine scalars):
    (p, s, p_c, x, d eps_q^p, yield state, converged)."""
    g = ratio * a * max(p_n, p_min)
    s = _added(s_n, dev_strain, 2.0 * g)
    p = elastic_pressure(p_n, strain, a, p_min)
    q_trial = objective.von_mises_of(s)
    if q_trial * q_trial / m2 + p * (p - pc_n) <= 0.0:
        return p, s, pc_n, 0.0, 0.0, ELASTIC, True
    p, q, pc, x, dg, converged = return_map(p_n, strain, q_trial, pc_n, a, b, 6.0 * g / m2, m2, p_min)
    s = objective.scaled(s, q / q_trial if q_trial > 0.0 else 0.0)
    return p, s, pc, x, 2.0 * dg * q / m2, SURFACE, converged


@njit(cache=True)
def _added(s, d, f):
    return (s[0] + f * d[0], s[1] + f * d[1], s[2] + f * d[2], s[3] + f * d[3], s[4] + f * d[4],
            s[5] + f * d[5], s[6] + f * d[6], s[7] + f * d[7], s[8] + f * d[8])


@njit(cache=True)
def elastic_work(p_n, q_n, p, q, elastic_strain, two_g):
    """sigma : d eps^e per volume over an increment: the volumetric part by the trapezoid rule,
    the deviatoric part (s - s_n = 2 G d e^e at a fixed G) exactly, (s:s - s_n:s_n) / (4 G),
    s:s = 2 q^2 / 3."""
    return 0.5 * (p_n + p) * elastic_strain + (q * q - q_n * q_n) / (3.0 * two_g)


@njit(cache=True)
def substepped(p_n, s_n, pc_n, strain, dev_strain, a, ratio, b, m2, p_min):
    """`increment` over the whole step, else over 2, 4, ... MOST_SUBSTEPS equal parts of it:
    (p, s, p_c, x, d eps_q^p, plastic work per volume, elastic work per volume, yield state)."""
    parts = 1
    while True:
        p, s, pc, x_sum, eq_sum, work, stored, state = p_n, s_n, pc_n, 0.0, 0.0, 0.0, 0.0, ELASTIC
        q = objective.von_mises_of(s_n)
        part = objective.scaled(dev_strain, 1.0 / parts)
        ok = True
        for _ in range(parts):
            p_0, q_0, two_g = p, q, 2.0 * ratio * a * max(p, p_min)
            p, s, pc, x, eq, sub_state, converged = increment(p, s, pc, strain / parts, part, a, ratio, b, m2, p_min)
            q = objective.von_mises_of(s)
            ok = ok and converged
            if sub_state != ELASTIC:
                state = sub_state
                # sigma : d eps_p, compression positive p with compression positive x
                work += p * x + q * eq
            stored += elastic_work(p_0, q_0, p, q, strain / parts - x, two_g)
            x_sum += x
            eq_sum += eq
        if ok:
            return p, s, pc, x_sum, eq_sum, work, stored, state
        if parts >= MOST_SUBSTEPS:
            return p, s, pc, x_sum, eq_sum, work, stored, UNCONVERGED
        parts *= 2


@njit(parallel=True, cache=True)
def _update(L, stress, eps_p, state, pc, volume, volume0, work, stored, dt, one_plus_e0, kappa, ratio,
            lam_minus_kappa, m2, p_min, threads):
    """The stress update; returns the largest (1 + e) max(p, p_min) of each thread's block."""
    bounds = block_bounds(L.shape[0], threads)
    stiffest = np.zeros(threads)
    for t in prange(threads):
        stiffest[t] = _update_block(bounds[t], bounds[t + 1], L, stress, eps_p, state, pc, volume, volume0, work,
                                    stored, dt, one_plus_e0, kappa, ratio, lam_minus_kappa, m2, p_min)
    return stiffest


@njit(cache=True)
def _update_block(lo, hi, L, stress, eps_p, state, pc, volume, volume0, work, stored, dt, one_plus_e0, kappa,
                  ratio, lam_minus_kappa, m2, p_min):
    stiffest = 0.0
    for p in range(lo, hi):
        D, w21, w02, w10 = objective.rate_parts(L[p])
        sigma = objective.rotated(stress[p], w21, w02, w10, dt)
        one_e = one_plus_e0 * volume[p] / volume0[p]
        dev_strain = objective.trial_deviator(objective.NO_STRESS, D, dt)
        mean, s, pc[p], x, eq, w, e, state[p] = substepped(
            objective.mean_pressure(sigma), objective.trial_deviator(sigma, D, 0.0), pc[p],
            -objective.trace(D) * dt, dev_strain, one_e / kappa, ratio, one_e / lam_minus_kappa, m2, p_min)
        eps_p[p] += eq
        work[p] += volume[p] * w
        stored[p] += volume[p] * e
        objective.assemble_from(s, mean, stress[p])
        stiffest = max(stiffest, one_e * max(mean, p_min))
    return stiffest


class ModifiedCamClay:
    """Effective stress: the stress it keeps is sigma' (a pore pressure would come on top)."""

    stress_sets_wave_speed = True   # its stiffness follows p' (solver/stepper.py, solver/step/fused.py)

    def __init__(self, config, dimension: int):
        self.config = config
        self.dimension = dimension
        self.density = config.density
        self.one_plus_e0 = 1.0 + config.initial_void_ratio
        self.kappa = config.kappa
        self.lam_minus_kappa = config.lambda_ - config.kappa
        self.m2 = config.critical_state_slope ** 2
        self.ratio = config.shear_to_bulk()
        self.p_min = config.floor_pressure
        self.wave_speed = config.dilatational_wave_speed()

    def _set_wave_speed(self, stiffest: float) -> None:
        """From the largest (1 + e) max(p, p_min): K = that / kappa."""
        bulk = stiffest / self.kappa
        self.wave_speed = math.sqrt(bulk * (1.0 + 4.0 * self.ratio / 3.0) / self.density)

    def init_particles(self, particles, sl: slice, scene) -> None:
        """p_c at least the ellipse through the initial stress (normally consolidated where the
        preconsolidation_pressure is below it); the wave speed of the initial stress."""
        p, q = invariants(particles.stress[sl])
        pc = particles.extra["preconsolidation_pressure"][sl]
        loaded = p > 0.0
        np.maximum(pc, np.where(loaded, p + q * q / (self.m2 * np.where(loaded, p, 1.0)), 0.0), out=pc)
        one_e = self.one_plus_e0 * particles.volume[sl] / particles.volume0[sl]
        stiffest = float(np.max(one_e * np.maximum(p, self.p_min), initial=0.0))
        self._set_wave_speed(max(stiffest, self.one_plus_e0 * self.p_min))
        particles.extra[ELASTIC_WORK][sl] = particles.volume[sl] * self._work_from_rest(p, q, one_e / self.kappa)

    def _work_from_rest(self, p: np.ndarray, q: np.ndarray, a: np.ndarray) -> np.ndarray:
        """The elastic work per volume that brings a stress-free particle to (p', q): the
        isotropic part along dp = a max(p, p_min) d eps_v (linear below the floor, exponential
        above it), then the shear at that p'. Exact for that path: V / a = V0 kappa / (1 + e0)
        whatever the volume. The strain energy's start, so that it reads as what the body
        holds, not only what it gained."""
        floor = self.p_min
        isotropic = np.where(p <= floor, p * p / (2.0 * a * floor), floor / (2.0 * a) + (p - floor) / a)
        return isotropic + q * q / (6.0 * self.ratio * a * np.maximum(p, floor))

    def update_stress(self, particles, sl: slice, dt: float) -> None:
        stiffest = _update(particles.L[sl], particles.stress[sl], particles.extra["plastic_strain"][sl],
                           particles.extra["yield_state"][sl], particles.extra["preconsolidation_pressure"][sl],
                           particles.volume[sl], particles.volume0[sl], particles.extra["plastic_work"][sl],
                           particles.extra[ELASTIC_WORK][sl], dt,
                           self.one_plus_e0, self.kappa, self.ratio, self.lam_minus_kappa, self.m2, self.p_min,
                           numba.get_num_threads())
        self._set_wave_speed(max(float(stiffest.max()), self.one_plus_e0 * self.p_min))

    def particle_strain_energy(self, particles, sl: slice) -> np.ndarray:
        """The elastic work done on each particle: from rest to its initial stress
        (`_work_from_rest`), then in each step's update. The model is hypoelastic: it has
        no stored energy function of the stress, and sigma : C^-1 : sigma / 2 with the moduli of
        the moment changes as p' alone does (G follows p'), which no work pays for."""
        return particles.extra[ELASTIC_WORK][sl].copy()

    def strain_energy(self, particles, sl: slice) -> float:
        return float(self.particle_strain_energy(particles, sl).sum())


def invariants(stress: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(p, q) of each 3x3 stress, p compression positive."""
    p = -np.trace(stress, axis1=1, axis2=2) / 3.0
    s = stress + p[:, None, None] * np.eye(3)
    return p, np.sqrt(1.5 * np.einsum("pab,pab->p", s, s))
