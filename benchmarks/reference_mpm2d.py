"""A hand-fused 2D MUSL step (linear hat functions, hypoelastic linear elasticity).

The speed reference of benchmarks/throughput.py: the same algorithm as
solver.stepper (Algorithm 1 of the Karamelo paper, no boundary conditions, no
body force), written as three numba loops with the 2x2 stencil unrolled by
hand and nothing shared between phases but the grid. It is not used by the
solver; tests/unit/test_benchmarks.py checks that it gives the solver's answer.
"""
from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _stencil(px, py, x0, y0, inv_h, nx):
    """The first of the particle's 2 x 2 nodes and the hat weights of its nodes along x and along y."""
    sx = (px - x0) * inv_h
    sy = (py - y0) * inv_h
    i = int(sx)
    j = int(sy)
    fx = sx - i
    fy = sy - j
    return i + nx * j, (1.0 - fx, fx), (1.0 - fy, fy)


@njit(cache=True)
def _musl_step(dt, alpha, x, x_old, v, F, stress, mass, vol0, vol, x0, y0, h, nx, gm, gp, gf, gv0, gv1, lam, mu):
    inv_h = 1.0 / h
    n = x.shape[0]
    gm[:] = 0.0
    gp[:] = 0.0
    gf[:] = 0.0
    # P2G: mass, momentum, internal force
    for p in range(n):
        base, wx, wy = _stencil(x[p, 0], x[p, 1], x0, y0, inv_h, nx)
        m = mass[p]
        sxx, sxy, syy = vol[p] * stress[p, 0, 0], vol[p] * stress[p, 0, 1], vol[p] * stress[p, 1, 1]
        for b in range(2):
            for a in range(2):
                node = base + a + nx * b
                w = wx[a] * wy[b]
                gx = (2 * a - 1) * inv_h * wy[b]
                gy = wx[a] * (2 * b - 1) * inv_h
                gm[node] += w * m
                gp[node, 0] += w * m * v[p, 0]
                gp[node, 1] += w * m * v[p, 1]
                gf[node, 0] -= sxx * gx + sxy * gy
                gf[node, 1] -= sxy * gx + syy * gy
    for node in range(gm.shape[0]):
        if gm[node] > 0.0:
            gv0[node, 0] = gp[node, 0] / gm[node]
            gv0[node, 1] = gp[node, 1] / gm[node]
            gv1[node, 0] = gv0[node, 0] + dt * gf[node, 0] / gm[node]
            gv1[node, 1] = gv0[node, 1] + dt * gf[node, 1] / gm[node]
        else:
            gv0[node, 0] = gv0[node, 1] = gv1[node, 0] = gv1[node, 1] = 0.0
    # G2P with the double mapping
    gp[:] = 0.0
    for p in range(n):
        base, wx, wy = _stencil(x[p, 0], x[p, 1], x0, y0, inv_h, nx)
        picx = picy = dvx = dvy = 0.0
        for b in range(2):
            for a in range(2):
                node = base + a + nx * b
                w = wx[a] * wy[b]
                picx += w * gv1[node, 0]
                picy += w * gv1[node, 1]
                dvx += w * (gv1[node, 0] - gv0[node, 0])
                dvy += w * (gv1[node, 1] - gv0[node, 1])
        x[p, 0] += dt * picx
        x[p, 1] += dt * picy
        v[p, 0] = alpha * (v[p, 0] + dvx) + (1 - alpha) * picx
        v[p, 1] = alpha * (v[p, 1] + dvy) + (1 - alpha) * picy
        m = mass[p]
        for b in range(2):
            for a in range(2):
                node = base + a + nx * b
                w = wx[a] * wy[b]
                gp[node, 0] += w * m * v[p, 0]
                gp[node, 1] += w * m * v[p, 1]
    for node in range(gm.shape[0]):
        if gm[node] > 0.0:
            gv1[node, 0] = gp[node, 0] / gm[node]
            gv1[node, 1] = gp[node, 1] / gm[node]
        else:
            gv1[node, 0] = gv1[node, 1] = 0.0
    # velocity gradient at the old positions, F, volume, stress
    for p in range(n):
        base, wx, wy = _stencil(x_old[p, 0], x_old[p, 1], x0, y0, inv_h, nx)
        lxx = lxy = lyx = lyy = 0.0
        for b in range(2):
            for a in range(2):
                node = base + a + nx * b
                gx = (2 * a - 1) * inv_h * wy[b]
                gy = wx[a] * (2 * b - 1) * inv_h
                lxx += gv1[node, 0] * gx
                lxy += gv1[node, 0] * gy
                lyx += gv1[node, 1] * gx
                lyy += gv1[node, 1] * gy
        f00, f01, f10, f11 = F[p, 0, 0], F[p, 0, 1], F[p, 1, 0], F[p, 1, 1]
        F[p, 0, 0] = f00 + dt * (lxx * f00 + lxy * f10)
        F[p, 0, 1] = f01 + dt * (lxx * f01 + lxy * f11)
        F[p, 1, 0] = f10 + dt * (lyx * f00 + lyy * f10)
        F[p, 1, 1] = f11 + dt * (lyx * f01 + lyy * f11)
        vol[p] = vol0[p] * (F[p, 0, 0] * F[p, 1, 1] - F[p, 0, 1] * F[p, 1, 0])
        tr = dt * (lxx + lyy)
        stress[p, 0, 0] += lam * tr + 2 * mu * dt * lxx
        stress[p, 1, 1] += lam * tr + 2 * mu * dt * lyy
        stress[p, 2, 2] += lam * tr
        shear = mu * dt * (lxy + lyx)
        stress[p, 0, 1] += shear
        stress[p, 1, 0] += shear


class ReferenceMPM2D:
    """Copies the state of a 2D ExplicitMPM (one linear elastic material) and steps it with `_musl_step`."""

    def __init__(self, x, v, F, stress, mass, vol0, vol, lower, h, nodes_x, n_nodes, flip_ratio, lam, mu):
        self.x, self.v, self.F, self.stress = x, v, F, stress
        self.mass, self.vol0, self.vol = mass, vol0, vol
        self.lower, self.h, self.nx = lower, h, nodes_x
        self.flip_ratio, self.lam, self.mu = flip_ratio, lam, mu
        self.grid = [np.zeros(n_nodes)] + [np.zeros((n_nodes, 2)) for _ in range(4)]
        self.x_old = np.empty_like(x)

    @classmethod
    def from_simulation(cls, sim) -> "ReferenceMPM2D":
        p, g = sim.particles, sim.grid
        (material, _), = sim.materials
        assert p.dimension == 2 and g.h[0] == g.h[1] and not sim.constraints.node.size and not sim.loads.any
        return cls(p.x.copy(), p.v.copy(), p.F.copy(), p.stress.copy(), p.mass.copy(), p.volume0.copy(),
                   p.volume.copy(), g.lower.copy(), float(g.h[0]), int(g.cells[0] + 1), g.n_nodes,
                   sim.flip_ratio, material.lam, material.mu)

    def advance(self, dt: float) -> None:
        self.x_old[:] = self.x
        gm, gp, gf, gv0, gv1 = self.grid
        _musl_step(dt, self.flip_ratio, self.x, self.x_old, self.v, self.F, self.stress, self.mass, self.vol0,
                   self.vol, self.lower[0], self.lower[1], self.h, self.nx, gm, gp, gf, gv0, gv1, self.lam, self.mu)
