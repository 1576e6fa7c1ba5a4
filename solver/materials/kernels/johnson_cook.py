"""Hypoelastic-plastic Johnson-Cook model with an EOS, damage and adiabatic heating
(Karamelo paper 2.4.2, eq. 2.8-2.16; review Appendix B.3, Algorithms 11-13).

Per particle and step (stress sigma = s - p I, p positive in compression):

1. objective rate: s <- Q s Q^T, the Hughes-Winget integration of the Jaumann
   rate (solver/materials/objective.py; the review's polar decomposition is the
   alternative it names);
2. elastic trial deviator: s_trial = s + 2 G' dt dev(D), G' = (1 - D) G;
3. radial return (Leroch et al., review Algorithm 12) on the flow stress
       sigma_f = (A + B eps_p^n) (1 + C ln(max(eps_dot_p / eps_dot_0, 1))) (1 - T*^m) (1 - D),
       T* = (T - T_room) / (T_melt - T_room) clamped to [0, 1],
   with eps_p, T and D of the start of the step; if q_trial = sqrt(3/2 s:s) > sigma_f,
   d eps_p solves q_trial - 3 G' d eps_p = sigma_f(eps_dot_p = d eps_p / dt) and
   s <- s_trial sigma_f / q_trial. The rate is this step's plastic rate, solved for
   (VERIFICATION_CASES F34 leaves it open): the previous step's rate, as Karamelo
   uses, makes the return alternate between yielding twice as fast and not at all
   once C ln(rate) is larger than the hardening of one step;
4. adiabatic heating: dT = taylor_quinney sigma_f d eps_p / (rho c_p) (eq. 2.13);
5. pressure from the EOS (solver/materials/eos.py) at rho = mass / volume and
   e = rho0 c_p (T - T_room) (one specific heat serves as c_p and c_v); a tension
   is scaled by (1 - D) (Karamelo's implementation; eq. 2.8 scales the compression
   branch, which would let a broken material pass through itself);
6. failure and damage (solver/materials/damage.py), updated after the stress as in
   Algorithm 11: they act from the next step on, except failure, which drops the
   deviator and any tension at once.

Per-particle state: plastic_strain, plastic_strain_rate, temperature (the body's
initial_temperature, else room_temperature), plastic_work (J: sigma_f d eps_p V summed,
sigma_f the returned stress's q; solver/materials/plastic_work.py), and damage (+ damage_init) only when
the material has a damage model or a failure criterion (declared, with their start
values, in solver/materials/johnson_cook.py).
The stored energy is a function of the current state, the energy of the stress
the particle carries: s:s / (4 G') per unit volume plus the work of the EOS's
cold pressure to the current mu (eos.stored_energy), in tension times (1 - D) as
the pressure is. A failed particle thus stores nothing once its debris expands
(the EOS energy of its growing volume, K (J - 1 - ln J), would otherwise grow
without bound and trip the runner's energy-growth check).
"""
from __future__ import annotations

import math

import numba
import numpy as np
from solver.jit import njit, prange

from solver.materials.kernels import damage as damage_model
from solver.materials.kernels import eos, objective
from solver.materials.kernels.elastic import IsotropicElastic
from solver.threads import block_bounds

# Layout of the flow-stress parameter array.
A, B, N, C, RATE0, M, T_ROOM, T_MELT, CHI, CP, RHO0 = range(11)


@njit(cache=True)
def homologous_temperature(prm, T):
    t = (T - prm[T_ROOM]) / (prm[T_MELT] - prm[T_ROOM])
    return min(max(t, 0.0), 1.0)


@njit(cache=True)
def flow_stress(prm, eps_p, rate_ratio, t_star):
    """Johnson-Cook flow stress without the damage factor."""
    hardening = prm[A] + prm[B] * eps_p ** prm[N] if eps_p > 0.0 else prm[A]
    rate = 1.0 + prm[C] * math.log(rate_ratio) if rate_ratio > 1.0 else 1.0
    thermal = 1.0 - t_star ** prm[M] if t_star > 0.0 else 1.0   # (no pow at room temperature)
    return hardening * rate * thermal


# Newton stops when its predicted next error is below this relative to the root: the
# root's own round-off (the residual q - 3 G x cancels to about this times q).
ROUND_OFF = 2.0 ** -52


@njit(cache=True)
def plastic_increment(q_trial, three_g, sigma_static, C, rate_floor, guess):
    """d eps_p of the radial return with the strain-rate term taken at this step's rate:

        g(d) = q_trial - 3 G' d - sigma_static (1 + C ln(max(d / rate_floor, 1))) = 0,

    rate_floor = eps_dot_0 dt, sigma_static the flow stress without its rate factor.
    g falls with d, so the root is unique; safeguarded Newton finds it, starting from
    `guess` (the last step's increment: in steady flow a step or two away).

    Stopping: g is convex, g'' = sigma_static C / d^2, so a Newton step of size h from
    x leaves an error of about h^2 |g''| / (2 |g'|) = (h / x)^2 x k / 2 with
    k = (sigma_static C / x) / |g'(x)| < 1. Once (h / x)^2 k <= ROUND_OFF the next
    iterate is the root to round-off: stop there instead of taking another step to
    confirm it (a test on |h| alone, near round-off, costs 2-3 more logarithms).
    """
    d = (q_trial - sigma_static) / three_g           # the root without the rate term, an upper bound
    if C == 0.0 or d <= rate_floor:
        return d
    lo, hi = rate_floor, d
    x = guess if lo < guess < hi else d
    for _ in range(60):
        g = q_trial - three_g * x - sigma_static * (1.0 + C * math.log(x / rate_floor))
        if g == 0.0:                                 # an exact root (else it would become a bracket end)
            return x
        if g > 0.0:
            lo = x
        else:
            hi = x
        curvature = sigma_static * C / x             # x |g''(x)|
        slope = three_g + curvature                  # |g'(x)|
        step = g / slope
        nxt = x + step
        if lo < nxt < hi:
            if step * step * curvature <= ROUND_OFF * x * x * slope:
                return nxt
        else:                                        # Newton left the bracket: bisect
            nxt = 0.5 * (lo + hi)
            if hi - lo <= ROUND_OFF * hi:
                return nxt
        x = nxt
    return x


@njit(parallel=True, cache=True)
def _update(L, stress, mass, volume, eps_p, eps_rate, T, work, dmg, d_init, dt, G, prm, eos_prm, dmg_prm, fail_prm,
            threads):
    """Update the particles' stress and state; returns the largest wave speed (K_t + 4/3 G') / rho."""
    bounds = block_bounds(L.shape[0], threads)
    fastest = np.zeros(threads)
    for t in prange(threads):
        fastest[t] = _update_block(bounds[t], bounds[t + 1], L, stress, mass, volume, eps_p, eps_rate, T, work, dmg,
                                   d_init, dt, G, prm, eos_prm, dmg_prm, fail_prm)
    return math.sqrt(fastest.max())


@njit(cache=True)
def _update_block(lo, hi, L, stress, mass, volume, eps_p, eps_rate, T, work, dmg, d_init, dt, G, prm, eos_prm, dmg_prm,
                  fail_prm):
    # the stress in nine scalars from the rotation to the store (kernels/objective.py says why)
    damaged = dmg.shape[0] > 0
    accumulates = d_init.shape[0] > 0
    fastest = 0.0
    for p in range(lo, hi):
        D, w21, w02, w10 = objective.rate_parts(L[p])
        d = dmg[p] if damaged else 0.0
        g = (1.0 - d) * G

        # deviator: elastic trial and radial return on the flow stress
        s = objective.trial_deviator(objective.rotated(stress[p], w21, w02, w10, dt), D, 2.0 * g * dt)
        q = objective.von_mises_of(s)
        t_star = homologous_temperature(prm, T[p])
        sigma_f = flow_stress(prm, eps_p[p], 1.0, t_star) * (1.0 - d)   # static: rate factor 1
        d_eps = 0.0
        if d >= 1.0:
            s = objective.NO_STRESS
        elif q > sigma_f:
            d_eps = plastic_increment(q, 3.0 * g, sigma_f, prm[C], prm[RATE0] * dt, eps_rate[p] * dt)
            sigma_f = q - 3.0 * g * d_eps
            s = objective.scaled(s, sigma_f / q)
            work[p] += volume[p] * sigma_f * d_eps     # sigma_{n+1} : d eps_p, as the heat below
        eps_p[p] += d_eps
        eps_rate[p] = d_eps / dt

        # heat, then pressure
        rho = mass[p] / volume[p]
        T[p] += prm[CHI] * sigma_f * d_eps / (rho * prm[CP])
        mu = rho / prm[RHO0] - 1.0
        pressure = eos.pressure(eos_prm, mu, prm[RHO0] * prm[CP] * (T[p] - prm[T_ROOM]))
        if pressure < 0.0:
            pressure *= 1.0 - d

        # failure at once; damage from the next step on
        if damaged:
            if damage_model.fails(fail_prm, eps_p[p], pressure):
                dmg[p] = 1.0
                s = objective.NO_STRESS
                pressure = max(pressure, 0.0)
            elif accumulates:
                d_init[p], d_new = damage_model.accumulate(
                    dmg_prm, d_init[p], d_eps, pressure, objective.von_mises_of(s), eps_rate[p] / prm[RATE0], t_star)
                dmg[p] = max(dmg[p], d_new)
        objective.assemble_from(s, pressure, stress[p])

        fastest = max(fastest, (eos.bulk_tangent(eos_prm, mu) + 4.0 / 3.0 * g) / rho)
    return fastest   # squared: one square root for all particles


@njit(parallel=True, cache=True)
def _energy(stress, mass, volume, dmg, G, rho0, eos_prm, out):
    damaged = dmg.shape[0] > 0
    for p in prange(stress.shape[0]):
        d = dmg[p] if damaged else 0.0
        g = (1.0 - d) * G
        mean = (stress[p, 0, 0] + stress[p, 1, 1] + stress[p, 2, 2]) / 3.0
        ss = 0.0   # s:s of the deviator s = sigma - mean I
        for a in range(3):
            for b in range(3):
                sab = stress[p, a, b] - (mean if a == b else 0.0)
                ss += sab * sab
        mu = mass[p] / (volume[p] * rho0) - 1.0
        shear = volume[p] * ss / (4.0 * g) if g > 0.0 else 0.0
        volumetric = mass[p] / rho0 * eos.stored_energy(eos_prm, mu)
        if mu < 0.0:   # tension carries (1 - D) of the EOS pressure: a failed particle stores nothing
            volumetric *= 1.0 - d
        out[p] = shear + volumetric


class JohnsonCook(IsotropicElastic):
    total_stress = True   # the EOS gives the whole pressure each step: 3 K0 alpha (T - T0) off it

    def __init__(self, config, dimension: int):
        super().__init__(config, dimension)
        self.config = config
        # m and specific_heat may be absent where unused (no heating, every temperature the room's):
        # then T* = 0, 1 - T*^m = 1 for any m > 0, and dT = 0, e = 0 for any specific heat
        self.flow = np.array([config.A, config.B, config.n, config.C, config.reference_strain_rate,
                              1.0 if config.m is None else config.m,
                              config.room_temperature, config.melt_temperature, config.taylor_quinney,
                              1.0 if config.specific_heat is None else config.specific_heat, config.density])
        self.eos = eos.parameters(config)
        self.bulk = eos.reference_bulk(self.eos)
        self.damage = damage_model.parameters(config.damage)
        self.failure = damage_model.failure_parameters(config.failure)
        self.reference_wave_speed = math.sqrt((self.bulk + 4.0 / 3.0 * self.mu) / self.density)
        self.wave_speed = self.reference_wave_speed

    @property
    def thermal_bulk_modulus(self) -> float:
        return self.bulk

    def _optional(self, particles, name: str, sl: slice) -> np.ndarray:
        return particles.extra[name][sl] if name in particles.extra else np.zeros(0)

    def update_stress(self, particles, sl: slice, dt: float) -> None:
        x = particles.extra
        fastest = _update(particles.L[sl], particles.stress[sl],
                          particles.mass[sl], particles.volume[sl], x["plastic_strain"][sl],
                          x["plastic_strain_rate"][sl], x["temperature"][sl], x["plastic_work"][sl],
                          self._optional(particles, "damage", sl), self._optional(particles, "damage_init", sl),
                          dt, self.mu, self.flow, self.eos, self.damage, self.failure, numba.get_num_threads())
        # The EOS stiffens under compression: the time step follows the current state.
        self.wave_speed = max(self.reference_wave_speed, fastest)

    def particle_strain_energy(self, particles, sl: slice) -> np.ndarray:
        out = np.empty(sl.stop - sl.start)
        _energy(particles.stress[sl], particles.mass[sl], particles.volume[sl],
                self._optional(particles, "damage", sl), self.mu, self.density, self.eos, out)
        return out
