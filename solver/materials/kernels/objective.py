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
"""
from __future__ import annotations

import math

from numba import njit


@njit(cache=True)
def rate_tensors(Lp, D, W):
    """D = sym(L), W = skew(L), padded to 3x3 with zeros."""
    dim = Lp.shape[0]
    for a in range(3):
        for b in range(3):
            D[a, b] = 0.0
            W[a, b] = 0.0
    for a in range(dim):
        for b in range(dim):
            D[a, b] = 0.5 * (Lp[a, b] + Lp[b, a])
            W[a, b] = 0.5 * (Lp[a, b] - Lp[b, a])


@njit(cache=True)
def rotate(sigma, W, dt):
    """sigma <- Q sigma Q^T with the Hughes-Winget rotation Q of the spin W over dt.

    Written in scalars, the products in the order of the two 3x3 loops they replace
    (tmp = Q sigma, then tmp Q^T: the same bits): with Q and tmp as scratch arrays the
    rotation took 35 of Johnson-Cook's 171 ns a particle, in scalars 22 (docs/benchmarks.md)."""
    # W is skew, so only its three independent components matter: w = (W21, W02, W10).
    h = 0.5 * dt
    w0, w1, w2 = h * W[2, 1], h * W[0, 2], h * W[1, 0]
    if w0 == 0.0 and w1 == 0.0 and w2 == 0.0:
        return
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
    s00, s01, s02 = sigma[0, 0], sigma[0, 1], sigma[0, 2]
    s10, s11, s12 = sigma[1, 0], sigma[1, 1], sigma[1, 2]
    s20, s21, s22 = sigma[2, 0], sigma[2, 1], sigma[2, 2]
    t00 = q00 * s00 + q01 * s10 + q02 * s20      # tmp = Q sigma
    t01 = q00 * s01 + q01 * s11 + q02 * s21
    t02 = q00 * s02 + q01 * s12 + q02 * s22
    t10 = q10 * s00 + q11 * s10 + q12 * s20
    t11 = q10 * s01 + q11 * s11 + q12 * s21
    t12 = q10 * s02 + q11 * s12 + q12 * s22
    t20 = q20 * s00 + q21 * s10 + q22 * s20
    t21 = q20 * s01 + q21 * s11 + q22 * s21
    t22 = q20 * s02 + q21 * s12 + q22 * s22
    sigma[0, 0] = t00 * q00 + t01 * q01 + t02 * q02   # sigma = tmp Q^T
    sigma[0, 1] = t00 * q10 + t01 * q11 + t02 * q12
    sigma[0, 2] = t00 * q20 + t01 * q21 + t02 * q22
    sigma[1, 0] = t10 * q00 + t11 * q01 + t12 * q02
    sigma[1, 1] = t10 * q10 + t11 * q11 + t12 * q12
    sigma[1, 2] = t10 * q20 + t11 * q21 + t12 * q22
    sigma[2, 0] = t20 * q00 + t21 * q01 + t22 * q02
    sigma[2, 1] = t20 * q10 + t21 * q11 + t22 * q12
    sigma[2, 2] = t20 * q20 + t21 * q21 + t22 * q22


@njit(cache=True)
def split(sigma, s):
    """Deviator s of sigma; returns the pressure p = -tr(sigma) / 3 (positive in compression)."""
    p = -(sigma[0, 0] + sigma[1, 1] + sigma[2, 2]) / 3.0
    for a in range(3):
        for b in range(3):
            s[a, b] = sigma[a, b]
        s[a, a] += p
    return p


@njit(cache=True)
def von_mises(s):
    """sqrt(3/2 s:s) of a deviator."""
    ss = 0.0
    for a in range(3):
        for b in range(3):
            ss += s[a, b] * s[a, b]
    return math.sqrt(1.5 * ss)


@njit(cache=True)
def add_deviatoric_rate(s, D, two_g_dt):
    """s <- s + 2 G dt dev(D); returns tr(D)."""
    tr = D[0, 0] + D[1, 1] + D[2, 2]
    for a in range(3):
        for b in range(3):
            s[a, b] += two_g_dt * D[a, b]
        s[a, a] -= two_g_dt * tr / 3.0
    return tr


@njit(cache=True)
def assemble(s, p, sigma):
    """sigma = s - p I."""
    for a in range(3):
        for b in range(3):
            sigma[a, b] = s[a, b]
        sigma[a, a] -= p


# The elastic trial of a hypoelastic-plastic step is these four calls in the plastic models'
# particle loops (J2, Drucker-Prager, Mohr-Coulomb): rate_tensors(L_p, D, W); rotate(sigma_p,
# W, dt); p = split(sigma_p, s); p -= K add_deviatoric_rate(s, D, 2 G dt) dt. Written
# once as a function, inlined by numba (inline="always") or called, the J2 kernel took 1.5x
# and 2x as long as with the calls written out (docs/benchmarks.md, "Speed, fifth part").
