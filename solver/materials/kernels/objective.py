"""Objective stress rate and small tensor helpers shared by the hypoelastic-plastic models.

Hypoelastic models integrate a stress *rate*; to stay objective (a rigid
rotation must not create stress, review B.3) the rate is the Jaumann rate

    sigma_dot = C : D + W sigma - sigma W,   D = sym(L), W = skew(L).

The spin part is integrated with the Hughes-Winget rotation
Q = (I - W dt/2)^-1 (I + W dt/2), sigma <- Q sigma Q^T: Q is orthogonal to
round-off, so a rigid rotation keeps the stress invariants exactly and turns the
stress by 2 atan(|w| dt / 2) per step instead of |w| dt (an angle error of
theta (w dt)^2 / 12 after turning by theta).

Velocity gradients are (dim, dim); stresses and rates are always 3x3. In 1D and
2D the missing components of D are zero (uniaxial / plane strain); axisymmetric
scenes carry a 3x3 L whose (2, 2) entry is the hoop rate v_r / r.

The plastic models' particle loops (J2, Drucker-Prager, Mohr-Coulomb, Johnson-Cook) keep a
particle's stress, rate and trial deviator in nine scalars each (a tuple, row by row) from
the rotation to the store: the trial stress is

    D, w21, w02, w10 = rate_parts(L_p)
    sigma = rotated(stress_p, w21, w02, w10, dt)
    p = mean_pressure(sigma) - K trace(D) dt
    s = trial_deviator(sigma, D, 2 G dt)

and assemble_from(s, p, stress_p) stores sigma = s - p I. Through 3x3 scratch arrays (D, W,
Q, Q sigma, s) the same operations took longer: Johnson-Cook's update 1.27x as long on the
Taylor bar (docs/benchmarks.md, issue 18); written as one function inlined by numba
(inline="always"), J2's took 1.5x as long as with the calls written out.
"""
from __future__ import annotations

import math

from solver.jit import njit


NO_STRESS = (0.0,) * 9


@njit(cache=True)
def rate_parts(Lp):
    """D = sym(L) (nine scalars) and the spin's independent components (W21, W02, W10), W = skew(L),
    both padded with zeros where L has fewer dimensions."""
    dim = Lp.shape[0]
    d01 = d02 = d12 = d11 = d22 = w21 = w02 = w10 = 0.0
    d00 = 0.5 * (Lp[0, 0] + Lp[0, 0])
    if dim > 1:
        d01, d11 = 0.5 * (Lp[0, 1] + Lp[1, 0]), 0.5 * (Lp[1, 1] + Lp[1, 1])
        w10 = 0.5 * (Lp[1, 0] - Lp[0, 1])
    if dim > 2:
        d02, d12, d22 = 0.5 * (Lp[0, 2] + Lp[2, 0]), 0.5 * (Lp[1, 2] + Lp[2, 1]), 0.5 * (Lp[2, 2] + Lp[2, 2])
        w21, w02 = 0.5 * (Lp[2, 1] - Lp[1, 2]), 0.5 * (Lp[0, 2] - Lp[2, 0])
    return (d00, d01, d02, d01, d11, d12, d02, d12, d22), w21, w02, w10


@njit(cache=True)
def rotated(sigma, w21, w02, w10, dt):
    """Q sigma Q^T (row by row, nine scalars) with the Hughes-Winget rotation Q of the spin
    whose independent components are (W21, W02, W10), over dt.

    Written in scalars, the products in the order of the two 3x3 loops they replace
    (tmp = Q sigma, then tmp Q^T: the same bits): with Q and tmp as scratch arrays the
    rotation took 35 of Johnson-Cook's 171 ns a particle, in scalars 22 (docs/benchmarks.md)."""
    s00, s01, s02 = sigma[0, 0], sigma[0, 1], sigma[0, 2]
    s10, s11, s12 = sigma[1, 0], sigma[1, 1], sigma[1, 2]
    s20, s21, s22 = sigma[2, 0], sigma[2, 1], sigma[2, 2]
    h = 0.5 * dt
    w0, w1, w2 = h * w21, h * w02, h * w10
    if w0 == 0.0 and w1 == 0.0 and w2 == 0.0:
        return s00, s01, s02, s10, s11, s12, s20, s21, s22
    # Cayley transform: Q = I + 2 / (1 + |w|^2) (Wh + Wh^2), Wh = W dt/2.
    c = 2.0 / (1.0 + w0 * w0 + w1 * w1 + w2 * w2)
    q00 = 1.0 - c * (w1 * w1 + w2 * w2)
    q11 = 1.0 - c * (w0 * w0 + w2 * w2)
    q22 = 1.0 - c * (w0 * w0 + w1 * w1)
    q01 = c * (w0 * w1 - w2)
    q10 = c * (w0 * w1 + w2)
    q02 = c * (w0 * w2 + w1)
    q20 = c * (w0 * w2 - w1)
    q12 = c * (w1 * w2 - w0)
    q21 = c * (w1 * w2 + w0)
    t00 = q00 * s00 + q01 * s10 + q02 * s20      # tmp = Q sigma
    t01 = q00 * s01 + q01 * s11 + q02 * s21
    t02 = q00 * s02 + q01 * s12 + q02 * s22
    t10 = q10 * s00 + q11 * s10 + q12 * s20
    t11 = q10 * s01 + q11 * s11 + q12 * s21
    t12 = q10 * s02 + q11 * s12 + q12 * s22
    t20 = q20 * s00 + q21 * s10 + q22 * s20
    t21 = q20 * s01 + q21 * s11 + q22 * s21
    t22 = q20 * s02 + q21 * s12 + q22 * s22
    return (t00 * q00 + t01 * q01 + t02 * q02, t00 * q10 + t01 * q11 + t02 * q12,   # tmp Q^T
            t00 * q20 + t01 * q21 + t02 * q22, t10 * q00 + t11 * q01 + t12 * q02,
            t10 * q10 + t11 * q11 + t12 * q12, t10 * q20 + t11 * q21 + t12 * q22,
            t20 * q00 + t21 * q01 + t22 * q02, t20 * q10 + t21 * q11 + t22 * q12,
            t20 * q20 + t21 * q21 + t22 * q22)


@njit(cache=True)
def mean_pressure(sigma):
    """p = -tr(sigma) / 3, positive in compression."""
    return -(sigma[0] + sigma[4] + sigma[8]) / 3.0


@njit(cache=True)
def trace(D):
    return D[0] + D[4] + D[8]


@njit(cache=True)
def trial_deviator(sigma, D, two_g_dt):
    """The deviator of sigma plus 2 G dt dev(D)."""
    p = mean_pressure(sigma)
    third = two_g_dt * trace(D) / 3.0
    return ((sigma[0] + p + two_g_dt * D[0]) - third, sigma[1] + two_g_dt * D[1], sigma[2] + two_g_dt * D[2],
            sigma[3] + two_g_dt * D[3], (sigma[4] + p + two_g_dt * D[4]) - third, sigma[5] + two_g_dt * D[5],
            sigma[6] + two_g_dt * D[6], sigma[7] + two_g_dt * D[7], (sigma[8] + p + two_g_dt * D[8]) - third)


@njit(cache=True)
def von_mises_of(s):
    """sqrt(3/2 s:s) of a deviator."""
    ss = s[0] * s[0] + s[1] * s[1] + s[2] * s[2] + s[3] * s[3] + s[4] * s[4] + s[5] * s[5] + s[6] * s[6]
    return math.sqrt(1.5 * (ss + s[7] * s[7] + s[8] * s[8]))


@njit(cache=True)
def scaled(s, f):
    return s[0] * f, s[1] * f, s[2] * f, s[3] * f, s[4] * f, s[5] * f, s[6] * f, s[7] * f, s[8] * f


@njit(cache=True)
def assemble_from(s, p, sigma):
    """sigma = s - p I, stored into the 3x3 array `sigma`."""
    sigma[0, 0], sigma[0, 1], sigma[0, 2] = s[0] - p, s[1], s[2]
    sigma[1, 0], sigma[1, 1], sigma[1, 2] = s[3], s[4] - p, s[5]
    sigma[2, 0], sigma[2, 1], sigma[2, 2] = s[6], s[7], s[8] - p
