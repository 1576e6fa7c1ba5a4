"""Exact solution of the Riemann problem of the 1D Euler equations, ideal gas.

The classic construction (Toro, Riemann Solvers and Numerical Methods for Fluid
Dynamics, ch. 4): the star pressure p* solves f_L(p*) + f_R(p*) + u_R - u_L = 0,
where f_K is the velocity jump across a shock (p > p_K, Rankine-Hugoniot) or a
rarefaction (p <= p_K, isentropic); f is monotone and concave, so Newton from the
two-rarefaction guess converges. The solution is self-similar in (x - x0) / t.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class State:
    rho: float
    u: float
    p: float


@dataclass(frozen=True)
class Solution:
    left: State
    right: State
    gamma: float
    p_star: float
    u_star: float
    rho_star_left: float
    rho_star_right: float

    def _speeds(self):
        g, L, R = self.gamma, self.left, self.right
        cL, cR = math.sqrt(g * L.p / L.rho), math.sqrt(g * R.p / R.rho)
        c_star_L = cL * (self.p_star / L.p) ** ((g - 1) / (2 * g))
        if self.p_star > L.p:   # left shock
            left_head = left_tail = L.u - cL * math.sqrt((g + 1) / (2 * g) * self.p_star / L.p + (g - 1) / (2 * g))
        else:                   # left rarefaction
            left_head, left_tail = L.u - cL, self.u_star - c_star_L
        c_star_R = cR * (self.p_star / R.p) ** ((g - 1) / (2 * g))
        if self.p_star > R.p:   # right shock
            right_head = right_tail = R.u + cR * math.sqrt((g + 1) / (2 * g) * self.p_star / R.p + (g - 1) / (2 * g))
        else:
            right_head, right_tail = R.u + cR, self.u_star + c_star_R
        return left_head, left_tail, right_tail, right_head, cL, cR

    def wave_positions(self, t: float, x0: float = 0.0) -> dict[str, float]:
        """Where the waves are at time t (left rarefaction head and tail, contact, right shock)."""
        left_head, left_tail, right_tail, right_head, _, _ = self._speeds()
        return {"left_head": x0 + left_head * t, "left_tail": x0 + left_tail * t,
                "contact": x0 + self.u_star * t, "right_tail": x0 + right_tail * t, "right_head": x0 + right_head * t}

    def sample(self, x: np.ndarray, t: float, x0: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(rho, u, p) at positions x and time t > 0."""
        g, L, R = self.gamma, self.left, self.right
        left_head, left_tail, right_tail, right_head, cL, cR = self._speeds()
        s = (np.asarray(x, dtype=float) - x0) / t
        rho, u, p = np.empty_like(s), np.empty_like(s), np.empty_like(s)
        for i, si in enumerate(s):
            if si < self.u_star:
                if si <= left_head:
                    state = (L.rho, L.u, L.p)
                elif si >= left_tail:
                    state = (self.rho_star_left, self.u_star, self.p_star)
                else:   # inside the left fan
                    ui = 2 / (g + 1) * (cL + (g - 1) / 2 * L.u + si)
                    ci = 2 / (g + 1) * (cL + (g - 1) / 2 * (L.u - si))
                    rhoi = L.rho * (ci / cL) ** (2 / (g - 1))
                    state = (rhoi, ui, L.p * (ci / cL) ** (2 * g / (g - 1)))
            else:
                if si >= right_head:
                    state = (R.rho, R.u, R.p)
                elif si <= right_tail:
                    state = (self.rho_star_right, self.u_star, self.p_star)
                else:   # inside the right fan
                    ui = 2 / (g + 1) * (-cR + (g - 1) / 2 * R.u + si)
                    ci = 2 / (g + 1) * (cR - (g - 1) / 2 * (R.u - si))
                    rhoi = R.rho * (ci / cR) ** (2 / (g - 1))
                    state = (rhoi, ui, R.p * (ci / cR) ** (2 * g / (g - 1)))
            rho[i], u[i], p[i] = state
        return rho, u, p


def _f(p: float, K: State, g: float) -> tuple[float, float]:
    """Velocity jump across the wave from state K to pressure p, and its derivative."""
    c = math.sqrt(g * K.p / K.rho)
    if p > K.p:   # shock
        A, B = 2 / ((g + 1) * K.rho), (g - 1) / (g + 1) * K.p
        root = math.sqrt(A / (p + B))
        return (p - K.p) * root, root * (1 - (p - K.p) / (2 * (B + p)))
    ratio = p / K.p   # rarefaction
    return 2 * c / (g - 1) * (ratio ** ((g - 1) / (2 * g)) - 1), ratio ** (-(g + 1) / (2 * g)) / (K.rho * c)


def solve(left: State, right: State, gamma: float = 1.4, tol: float = 1e-14) -> Solution:
    g = gamma
    cL, cR = math.sqrt(g * left.p / left.rho), math.sqrt(g * right.p / right.rho)
    if 2 * (cL + cR) / (g - 1) <= right.u - left.u:
        raise ValueError("the initial states create a vacuum")
    # two-rarefaction approximation as the starting guess
    z = (g - 1) / (2 * g)
    p = ((cL + cR - 0.5 * (g - 1) * (right.u - left.u)) / (cL / left.p**z + cR / right.p**z)) ** (1 / z)
    for _ in range(100):
        fL, dL = _f(p, left, g)
        fR, dR = _f(p, right, g)
        new = max(p - (fL + fR + right.u - left.u) / (dL + dR), tol)
        if abs(new - p) <= tol * 0.5 * (new + p):
            p = new
            break
        p = new
    fL, _ = _f(p, left, g)
    fR, _ = _f(p, right, g)
    u = 0.5 * (left.u + right.u) + 0.5 * (fR - fL)

    def star_density(K: State) -> float:
        if p > K.p:
            r = (g - 1) / (g + 1)
            return K.rho * (p / K.p + r) / (r * p / K.p + 1)
        return K.rho * (p / K.p) ** (1 / g)

    return Solution(left, right, g, p, u, star_density(left), star_density(right))


SOD_LEFT, SOD_RIGHT = State(1.0, 0.0, 1.0), State(0.125, 0.0, 0.1)
