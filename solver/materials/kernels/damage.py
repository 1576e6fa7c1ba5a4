"""Johnson-Cook damage (Karamelo eq. 2.14-2.16, review B.3.3 and Algorithm 13) and
failure by plastic strain or minimum pressure (MPM3DMP 5.3).

Initiation: D_init += d eps_p / eps_f with the failure strain

    eps_f = [D1 + D2 exp(D3 sigma*)] [1 + D4 ln(max(eps_dot_p / eps_dot_0, 1))] [1 + D5 T*],

sigma* = -p / sigma_eq the stress triaxiality (the rate is guarded like the flow
stress, VERIFICATION_CASES F34). Evolution: D = min(1, k (D_init - 1)) once
D_init >= 1. The sources disagree on k (VERIFICATION_CASES F14: the equations
print 10, Algorithm 13 prints 1) and cap nothing: k is the damage's
`evolution_factor` (default 10, the equations) and D is capped at 1.

Failure (optional `failure` of the material): a particle whose plastic strain
reaches `plastic_strain` or whose pressure falls below `min_pressure` fails
(D = 1 at once). A fully damaged or failed particle carries no deviatoric stress
and no tension; it still resists compression so that debris does not
interpenetrate (as Karamelo's EOS does for D = 1; MPM3DMP sets the whole stress
to zero, which is the same in tension).
"""
from __future__ import annotations

import math

import numpy as np
from solver.jit import njit

# Layout of the damage parameter array.
D1, D2, D3, D4, D5, EVOLUTION = range(6)
# Layout of the failure parameter array.
FAIL_STRAIN, FAIL_PRESSURE = range(2)


def parameters(damage) -> np.ndarray:
    if damage is None:
        return np.zeros(6)
    return np.array([damage.D1, damage.D2, damage.D3, damage.D4, damage.D5, damage.evolution_factor])


def failure_parameters(failure) -> np.ndarray:
    """[plastic strain at failure, minimum pressure]; inf / -inf where not given."""
    strain = math.inf if failure is None or failure.plastic_strain is None else failure.plastic_strain
    pressure = -math.inf if failure is None or failure.min_pressure is None else failure.min_pressure
    return np.array([strain, pressure])


@njit(cache=True)
def failure_strain(prm, triaxiality, rate_ratio, t_star):
    return ((prm[D1] + prm[D2] * math.exp(prm[D3] * triaxiality))
            * (1.0 + prm[D4] * math.log(max(rate_ratio, 1.0)))
            * (1.0 + prm[D5] * t_star))


@njit(cache=True)
def accumulate(prm, d_init, d_eps_p, pressure, sigma_eq, rate_ratio, t_star):
    """New (D_init, D) after a plastic strain increment d_eps_p."""
    if d_eps_p > 0.0 and sigma_eq > 0.0:
        eps_f = failure_strain(prm, -pressure / sigma_eq, rate_ratio, t_star)
        d_init += d_eps_p / eps_f if eps_f > 0.0 else math.inf
    damage = min(1.0, prm[EVOLUTION] * (d_init - 1.0)) if d_init >= 1.0 else 0.0
    return d_init, damage


@njit(cache=True)
def fails(prm, eps_p, pressure):
    return eps_p >= prm[FAIL_STRAIN] or pressure < prm[FAIL_PRESSURE]
