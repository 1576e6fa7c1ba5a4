"""Equations of state of the johnson_cook material: pressure from density (and heat).

Pressure is positive in compression. With mu = rho / rho0 - 1 (rho = mass / volume
of the particle, so it is right whatever the kinematics count as volume):

* ``linear``:        p = -K (J - 1) = K mu / (1 + mu),   J = rho0 / rho,
  K = E / (3 (1 - 2 nu)) of the material.
* ``mie_gruneisen``, compression (mu >= 0), Karamelo eq. 2.8 / review B.9 with D = 0:
      p = rho0 c0^2 mu [1 + (1 - gamma0 / 2) mu] / [1 - (s - 1) mu]^2 + gamma0 e
  (the papers write it with eta = 1 + mu: (eta - 1)[eta - gamma0/2 (eta - 1)] / [eta - s (eta - 1)]^2);
  tension (mu < 0), the linear branch of MPM3DMP eq. 18:
      p = rho0 c0^2 mu + gamma0 e
  with e = rho0 c_v (T - T_room) the thermal energy per unit volume (Karamelo eq. 2.10).
  The branch is chosen by mu >= 0, not by the sign of the result (the papers'
  criterion is circular: VERIFICATION_CASES F19). Beyond the limiting compression
  mu = 1 / (s - 1) the pressure is NaN, which the runner reports as an instability.
  Damage enters the pressure in solver/materials/johnson_cook.py, not here.

`bulk_tangent` is rho dp/drho, for the wave speed of the time step.
`stored_energy` is the work of the cold pressure (e = 0) per reference volume,
W = -int_1^J p dJ' = int_0^mu p / (1 + mu')^2 dmu': K (1 - J)^2 / 2 for the
linear EOS, rho0 c0^2 (ln(1 + mu) + 1 / (1 + mu) - 1) for the Mie-Gruneisen
tension branch, and for its compression branch a closed form too (`_hugoniot_work`;
8-point Gauss-Legendre for a Hugoniot slope s below 0.01). p^2 / (2K) would overstate it fivefold at the
mu ~ 1 of a hypervelocity impact and trip the runner's energy-growth check.
"""
from __future__ import annotations

import math

import numpy as np
from solver.jit import njit

LINEAR, MIE_GRUNEISEN = 0, 1
# Layout of the parameter array of one EOS.
KIND, BULK, RHO0_C0_SQ, SLOPE, GAMMA0 = range(5)


def parameters(config) -> np.ndarray:
    """The EOS of a johnson_cook material config as the float array the kernels read."""
    bulk = config.youngs_modulus / (3.0 * (1.0 - 2.0 * config.poisson_ratio))
    eos = config.eos
    if eos.model == "linear":
        return np.array([LINEAR, bulk, 0.0, 0.0, 0.0])
    return np.array([MIE_GRUNEISEN, config.density * eos.c0**2, config.density * eos.c0**2, eos.s, eos.gamma0])


def reference_bulk(prm: np.ndarray) -> float:
    """rho dp/drho at rest: K (linear) or rho0 c0^2 (Mie-Gruneisen)."""
    return float(prm[BULK])


@njit(cache=True)
def pressure(prm, mu, e):
    if prm[KIND] == LINEAR:
        return prm[BULK] * mu / (1.0 + mu)
    if mu >= 0.0:
        den = 1.0 - (prm[SLOPE] - 1.0) * mu
        if den <= 0.0:   # beyond the Hugoniot's limiting compression: the run is unstable
            return math.nan
        return prm[RHO0_C0_SQ] * mu * (1.0 + (1.0 - 0.5 * prm[GAMMA0]) * mu) / (den * den) + prm[GAMMA0] * e
    return prm[RHO0_C0_SQ] * mu + prm[GAMMA0] * e


@njit(cache=True)
def bulk_tangent(prm, mu):
    """rho dp/drho = (1 + mu) dp/dmu at constant e."""
    if prm[KIND] == LINEAR:
        return prm[BULK] / (1.0 + mu)
    if mu >= 0.0:
        a = 1.0 - 0.5 * prm[GAMMA0]
        b = prm[SLOPE] - 1.0
        den = 1.0 - b * mu
        if den <= 0.0:
            return math.nan
        dp = prm[RHO0_C0_SQ] * ((1.0 + 2.0 * a * mu) * den + 2.0 * b * mu * (1.0 + a * mu)) / (den * den * den)
        return (1.0 + mu) * dp
    return (1.0 + mu) * prm[RHO0_C0_SQ]


# Below this Hugoniot slope the two terms of _hugoniot_work cancel (as 1 / s): 8-point Gauss there
_CLOSED_FORM_SLOPE = 0.01
# log1p(r) - r by its series below this r (6 terms: relative error under r^5 = 1e-15), directly above
# it (cancellation: relative error 2 eps / r, under 5e-13)
_SERIES_R = 1e-3


@njit(cache=True)
def _hugoniot_work(s, gamma0, mu):
    """int_0^mu p_c / (1 + m)^2 dm / (rho0 c0^2) for the compression branch, p_c its cold pressure:
    partial fractions of m (1 + a m) / ((1 + m)^2 (1 - b m)^2), a = 1 - gamma0 / 2, b = s - 1, give

        gamma0 mu^2 / (2 s (1 - b mu) (1 + mu)) - (s - gamma0) / s^3 (ln(1 + r) - r),  r = s mu / (1 - b mu),

    each term of order mu^2 (the order-mu parts cancel in closed form, not in floating point).
    Against a 2000-point Gauss-Legendre integral: within 2e-11 (the reference's own accuracy next
    to the limit) for mu from 1e-9 to 0.99 of the limiting compression and s >= 0.05
    (tests/verification/test_plasticity.py), where the 8-point rule it replaces was off by 5e-4
    at 0.9 of the limit and 28 % at 0.99; 20 -> 13 ns a call."""
    b = s - 1.0
    den = 1.0 - b * mu
    if den <= 0.0:   # beyond the limiting compression, as `pressure`
        return math.nan
    r = s * mu / den
    if r < _SERIES_R:
        h = r * r * (-0.5 + r * (1.0 / 3.0 + r * (-0.25 + r * (0.2 + r * (-1.0 / 6.0)))))
    else:
        h = math.log1p(r) - r
    return gamma0 * mu * mu / (2.0 * s * den * (1.0 + mu)) - (s - gamma0) / (s * s * s) * h


# 8-point Gauss-Legendre nodes and weights on [-1, 1]
_GAUSS_X = np.array([-0.9602898564975363, -0.7966664774136267, -0.5255324099163290, -0.1834346424956498,
                     0.1834346424956498, 0.5255324099163290, 0.7966664774136267, 0.9602898564975363])
_GAUSS_W = np.array([0.1012285362903763, 0.2223810344533745, 0.3137066458778873, 0.3626837833783620,
                     0.3626837833783620, 0.3137066458778873, 0.2223810344533745, 0.1012285362903763])


@njit(cache=True)
def stored_energy(prm, mu):
    """Work of the cold pressure from rest to mu, per reference volume."""
    if prm[KIND] == LINEAR:
        j = 1.0 / (1.0 + mu)
        return 0.5 * prm[BULK] * (1.0 - j) * (1.0 - j)
    if mu < 0.0:
        return prm[RHO0_C0_SQ] * (math.log1p(mu) + 1.0 / (1.0 + mu) - 1.0)
    if prm[SLOPE] >= _CLOSED_FORM_SLOPE:
        return prm[RHO0_C0_SQ] * _hugoniot_work(prm[SLOPE], prm[GAMMA0], mu)
    w = 0.0
    for k in range(8):
        m = 0.5 * mu * (1.0 + _GAUSS_X[k])
        w += _GAUSS_W[k] * pressure(prm, m, 0.0) / ((1.0 + m) * (1.0 + m))
    return 0.5 * mu * w
