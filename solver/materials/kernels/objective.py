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
def rotate(sigma, W, dt, Q, tmp):
    """sigma <- Q sigma Q^T with the Hughes-Winget rotation Q of the spin W over dt."""
    # W is skew, so only its three independent components matter: w = (W21, W02, W10).
    h = 0.5 * dt
    w0, w1, w2 = h * W[2, 1], h * W[0, 2], h * W[1, 0]
    if w0 == 0.0 and w1 == 0.0 and w2 == 0.0:
        return
    # Cayley transform: Q = I + 2 / (1 + |w|^2) (Wh + Wh^2), Wh = W dt/2.
    c = 2.0 / (1.0 + w0 * w0 + w1 * w1 + w2 * w2)
    Q[0, 0] = 1.0 - c * (w1 * w1 + w2 * w2)
    Q[1, 1] = 1.0 - c * (w0 * w0 + w2 * w2)
    Q[2, 2] = 1.0 - c * (w0 * w0 + w1 * w1)
    Q[0, 1] = c * (w0 * w1 - w2)
    Q[1, 0] = c * (w0 * w1 + w2)
    Q[0, 2] = c * (w0 * w2 + w1)
    Q[2, 0] = c * (w0 * w2 - w1)
    Q[1, 2] = c * (w1 * w2 - w0)
    Q[2, 1] = c * (w1 * w2 + w0)
    for a in range(3):       # tmp = Q sigma
        for b in range(3):
            tmp[a, b] = Q[a, 0] * sigma[0, b] + Q[a, 1] * sigma[1, b] + Q[a, 2] * sigma[2, b]
    for a in range(3):       # sigma = tmp Q^T
        for b in range(3):
            sigma[a, b] = tmp[a, 0] * Q[b, 0] + tmp[a, 1] * Q[b, 1] + tmp[a, 2] * Q[b, 2]


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
# W, dt, Q, tmp); p = split(sigma_p, s); p -= K add_deviatoric_rate(s, D, 2 G dt) dt. Written
# once as a function, inlined by numba (inline="always") or called, the J2 kernel took 1.5x
# and 2x as long as with the calls written out (docs/benchmarks.md, "Speed, fifth part").
