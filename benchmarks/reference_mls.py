"""A minimal MLS-MPM step in numba: the speed ceiling of benchmarks/throughput.py.

The elastic-block step that benchmarks/throughput.py also runs in Taichi and in
Warp (benchmarks/frameworks/): quadratic B-splines, APIC (MLS: the stress folded
into the affine momentum, Hu et al. 2018), compressible neo-Hookean Kirchhoff
stress, float64, no boundary conditions (the block flies free over the few
steps measured). Every loop written out for its dimension, the 2D per-particle
and per-node work in helpers inlined into the loops (benchmarks/transfer_fusion.py
reuses them), each thread adding into its own copy of the grid (as the solver
does, solver/threads.py). Nothing of the solver is used, so it shows what the
solver's generality costs.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange


@njit(cache=True)
def _bspline(s):
    base = int(s - 0.5)
    f = s - base
    return base, f, (0.5 * (1.5 - f) ** 2, 0.75 - (f - 1.0) ** 2, 0.5 * (f - 0.5) ** 2)


@njit(cache=True, inline="always")
def gather_2d(dt, inv_dx, nx, x, v, C, grid_mom, p):
    """2D G2P of particle p: v_p and C_p from the grid's velocities (in grid_mom), x_p moved;
    returns v_p and C_p (inlined: no call level in the particle loop)."""
    bx, fx, wx = _bspline(x[p, 0] * inv_dx)
    by, fy, wy = _bspline(x[p, 1] * inv_dx)
    vx = vy = c00 = c01 = c10 = c11 = 0.0
    for j in range(3):
        dy = j - fy
        row = (by + j) * nx
        for i in range(3):
            dxi = i - fx
            w = wx[i] * wy[j]
            gvx, gvy = grid_mom[row + bx + i, 0], grid_mom[row + bx + i, 1]
            vx += w * gvx
            vy += w * gvy
            c00 += 4.0 * inv_dx * w * gvx * dxi
            c01 += 4.0 * inv_dx * w * gvx * dy
            c10 += 4.0 * inv_dx * w * gvy * dxi
            c11 += 4.0 * inv_dx * w * gvy * dy
    v[p, 0], v[p, 1] = vx, vy
    C[p, 0, 0], C[p, 0, 1], C[p, 1, 0], C[p, 1, 1] = c00, c01, c10, c11
    x[p, 0] += dt * vx
    x[p, 1] += dt * vy
    return vx, vy, c00, c01, c10, c11


@njit(cache=True, inline="always")
def own_zeroed(t, grid_mass, grid_mom, copies_mass, copies_mom):
    """Thread t's nodal arrays, zeroed: the grid itself for t = 0, else its own copy (so the
    zeroing runs in the threads, as solver/threads.py's `own_zeroed`)."""
    gm, gp = (grid_mass, grid_mom) if t == 0 else (copies_mass[t - 1], copies_mom[t - 1])
    gm[:] = 0.0
    gp[:, :] = 0.0
    return gm, gp


@njit(cache=True, inline="always")
def node_velocity_2d(node, grid_mass, grid_mom, copies_mass, copies_mom):
    """The threads' copies added into the node, then its velocity (mv) / m in grid_mom."""
    for t in range(copies_mass.shape[0]):
        grid_mass[node] += copies_mass[t, node]
        grid_mom[node, 0] += copies_mom[t, node, 0]
        grid_mom[node, 1] += copies_mom[t, node, 1]
    if grid_mass[node] > 0.0:
        grid_mom[node, 0] /= grid_mass[node]
        grid_mom[node, 1] /= grid_mass[node]


@njit(cache=True, inline="always")
def deform_2d(dt, F, p, c00, c01, c10, c11):
    """F_p <- (I + dt C_p) F_p."""
    f00, f01, f10, f11 = F[p, 0, 0], F[p, 0, 1], F[p, 1, 0], F[p, 1, 1]
    F[p, 0, 0] = f00 + dt * (c00 * f00 + c01 * f10)
    F[p, 0, 1] = f01 + dt * (c00 * f01 + c01 * f11)
    F[p, 1, 0] = f10 + dt * (c10 * f00 + c11 * f10)
    F[p, 1, 1] = f11 + dt * (c10 * f01 + c11 * f11)


@njit(cache=True, inline="always")
def scatter_affine_2d(dx, nx, bx, fx, wx, by, fy, wy, m, mvx, mvy, a00, a01, a10, a11, gm, gp):
    """A particle's mass and affine momentum w (m v + A (x_I - x_p)) into its 3 x 3 nodes."""
    for j in range(3):
        dy = (j - fy) * dx
        row = (by + j) * nx
        for i in range(3):
            dxi = (i - fx) * dx
            w = wx[i] * wy[j]
            node = row + bx + i
            gm[node] += w * m
            gp[node, 0] += w * (mvx + a00 * dxi + a01 * dy)
            gp[node, 1] += w * (mvy + a10 * dxi + a11 * dy)


@njit(cache=True, inline="always")
def scatter_2d(dt, inv_dx, nx, x, v, C, F, mass, vol, lam, mu, gm, gp, p):
    """2D P2G of particle p into gm, gp, its Kirchhoff stress formed from F_p and folded into
    the affine momentum (inlined: no call level in the particle loop)."""
    dx = 1.0 / inv_dx
    bx, fx, wx = _bspline(x[p, 0] * inv_dx)
    by, fy, wy = _bspline(x[p, 1] * inv_dx)
    f00, f01, f10, f11 = F[p, 0, 0], F[p, 0, 1], F[p, 1, 0], F[p, 1, 1]
    J = f00 * f11 - f01 * f10
    ln_j = lam * math.log(J)
    # Kirchhoff stress mu (F F^T - I) + lam ln J I (plane strain)
    t00 = mu * (f00 * f00 + f01 * f01 - 1.0) + ln_j
    t01 = mu * (f00 * f10 + f01 * f11)
    t11 = mu * (f10 * f10 + f11 * f11 - 1.0) + ln_j
    k = -dt * vol[p] * 4.0 * inv_dx * inv_dx
    m = mass[p]
    a00, a01 = k * t00 + m * C[p, 0, 0], k * t01 + m * C[p, 0, 1]
    a10, a11 = k * t01 + m * C[p, 1, 0], k * t11 + m * C[p, 1, 1]
    mvx, mvy = m * v[p, 0], m * v[p, 1]
    scatter_affine_2d(dx, nx, bx, fx, wx, by, fy, wy, m, mvx, mvy, a00, a01, a10, a11, gm, gp)


@njit(parallel=True, cache=True)
def p2g_2d(dt, inv_dx, nx, x, v, C, F, mass, vol, lam, mu, grid_mass, grid_mom, copies_mass, copies_mom):
    """The 2D step's P2G: each thread its block of particles into its own nodal arrays."""
    n = x.shape[0]
    threads = copies_mass.shape[0] + 1
    for t in prange(threads):
        gm, gp = own_zeroed(t, grid_mass, grid_mom, copies_mass, copies_mom)
        for p in range((n * t) // threads, (n * (t + 1)) // threads):
            scatter_2d(dt, inv_dx, nx, x, v, C, F, mass, vol, lam, mu, gm, gp, p)


@njit(parallel=True, cache=True)
def step_2d(dt, inv_dx, nx, x, v, C, F, mass, vol, lam, mu, grid_mass, grid_mom, copies_mass, copies_mom):
    n = x.shape[0]
    p2g_2d(dt, inv_dx, nx, x, v, C, F, mass, vol, lam, mu, grid_mass, grid_mom, copies_mass, copies_mom)
    for node in prange(grid_mass.shape[0]):
        node_velocity_2d(node, grid_mass, grid_mom, copies_mass, copies_mom)
    for p in prange(n):
        vx, vy, c00, c01, c10, c11 = gather_2d(dt, inv_dx, nx, x, v, C, grid_mom, p)
        deform_2d(dt, F, p, c00, c01, c10, c11)


@njit(parallel=True, cache=True)
def step_3d(dt, inv_dx, nx, x, v, C, F, mass, vol, lam, mu, grid_mass, grid_mom, copies_mass, copies_mom):
    dx = 1.0 / inv_dx
    n = x.shape[0]
    nxy = nx * nx
    threads = copies_mass.shape[0] + 1
    aff = np.empty((threads, 4, 3, 3))   # [t, 0]: each thread's 3x3 on cache lines of its own
    for t in prange(threads):
        gm, gp = own_zeroed(t, grid_mass, grid_mom, copies_mass, copies_mom)
        a = aff[t, 0]
        for p in range((n * t) // threads, (n * (t + 1)) // threads):
            bx, fx, wx = _bspline(x[p, 0] * inv_dx)
            by, fy, wy = _bspline(x[p, 1] * inv_dx)
            bz, fz, wz = _bspline(x[p, 2] * inv_dx)
            J = (F[p, 0, 0] * (F[p, 1, 1] * F[p, 2, 2] - F[p, 1, 2] * F[p, 2, 1])
                 - F[p, 0, 1] * (F[p, 1, 0] * F[p, 2, 2] - F[p, 1, 2] * F[p, 2, 0])
                 + F[p, 0, 2] * (F[p, 1, 0] * F[p, 2, 1] - F[p, 1, 1] * F[p, 2, 0]))
            ln_j = lam * math.log(J)
            k = -dt * vol[p] * 4.0 * inv_dx * inv_dx
            m = mass[p]
            for r in range(3):
                for c in range(3):
                    b = F[p, r, 0] * F[p, c, 0] + F[p, r, 1] * F[p, c, 1] + F[p, r, 2] * F[p, c, 2]
                    tau = mu * (b - (1.0 if r == c else 0.0)) + (ln_j if r == c else 0.0)
                    a[r, c] = k * tau + m * C[p, r, c]
            mvx, mvy, mvz = m * v[p, 0], m * v[p, 1], m * v[p, 2]
            for kk in range(3):
                dz = (kk - fz) * dx
                for j in range(3):
                    dy = (j - fy) * dx
                    row = (by + j) * nx + (bz + kk) * nxy
                    wyz = wy[j] * wz[kk]
                    for i in range(3):
                        dxi = (i - fx) * dx
                        w = wx[i] * wyz
                        node = row + bx + i
                        gm[node] += w * m
                        gp[node, 0] += w * (mvx + a[0, 0] * dxi + a[0, 1] * dy + a[0, 2] * dz)
                        gp[node, 1] += w * (mvy + a[1, 0] * dxi + a[1, 1] * dy + a[1, 2] * dz)
                        gp[node, 2] += w * (mvz + a[2, 0] * dxi + a[2, 1] * dy + a[2, 2] * dz)
    for node in prange(grid_mass.shape[0]):
        for t in range(threads - 1):
            grid_mass[node] += copies_mass[t, node]
            for c in range(3):
                grid_mom[node, c] += copies_mom[t, node, c]
        if grid_mass[node] > 0.0:
            for c in range(3):
                grid_mom[node, c] /= grid_mass[node]
    cmat = np.empty((threads, 4, 3, 3))
    fold = np.empty((threads, 4, 3, 3))
    for t in prange(threads):
        c_ = cmat[t, 0]
        f_ = fold[t, 0]
        for p in range((n * t) // threads, (n * (t + 1)) // threads):
            bx, fx, wx = _bspline(x[p, 0] * inv_dx)
            by, fy, wy = _bspline(x[p, 1] * inv_dx)
            bz, fz, wz = _bspline(x[p, 2] * inv_dx)
            vx = vy = vz = 0.0
            c_[:, :] = 0.0
            for kk in range(3):
                dz = kk - fz
                for j in range(3):
                    dy = j - fy
                    row = (by + j) * nx + (bz + kk) * nxy
                    for i in range(3):
                        dxi = i - fx
                        w = wx[i] * wy[j] * wz[kk]
                        node = row + bx + i
                        gv0, gv1, gv2 = grid_mom[node, 0], grid_mom[node, 1], grid_mom[node, 2]
                        vx += w * gv0
                        vy += w * gv1
                        vz += w * gv2
                        s = 4.0 * inv_dx * w
                        c_[0, 0] += s * gv0 * dxi
                        c_[0, 1] += s * gv0 * dy
                        c_[0, 2] += s * gv0 * dz
                        c_[1, 0] += s * gv1 * dxi
                        c_[1, 1] += s * gv1 * dy
                        c_[1, 2] += s * gv1 * dz
                        c_[2, 0] += s * gv2 * dxi
                        c_[2, 1] += s * gv2 * dy
                        c_[2, 2] += s * gv2 * dz
            v[p, 0], v[p, 1], v[p, 2] = vx, vy, vz
            x[p, 0] += dt * vx
            x[p, 1] += dt * vy
            x[p, 2] += dt * vz
            f_[:, :] = F[p]
            for r in range(3):
                for c in range(3):
                    C[p, r, c] = c_[r, c]
                    F[p, r, c] = f_[r, c] + dt * (c_[r, 0] * f_[0, c] + c_[r, 1] * f_[1, c] + c_[r, 2] * f_[2, c])


class ReferenceMLS:
    """The block of a solver scene (unit grid, origin 0), stepped by the functions above."""

    def __init__(self, x, v, mass, volume, cells: int, lam: float, mu: float, threads: int):
        self.dim = x.shape[1]
        self.x, self.v = x.copy(), v.copy()
        self.mass, self.vol = mass.copy(), volume.copy()
        self.C = np.zeros((x.shape[0], self.dim, self.dim))
        self.F = np.tile(np.eye(self.dim), (x.shape[0], 1, 1))
        self.inv_dx, self.nx = float(cells), cells + 1
        n_nodes = self.nx ** self.dim
        self.grid_mass, self.grid_mom = np.zeros(n_nodes), np.zeros((n_nodes, self.dim))
        self.copies_mass = np.zeros((threads - 1, n_nodes))
        self.copies_mom = np.zeros((threads - 1, n_nodes, self.dim))
        self.lam, self.mu = lam, mu
        self._step = step_2d if self.dim == 2 else step_3d

    def advance(self, dt: float) -> None:
        self._step(dt, self.inv_dx, self.nx, self.x, self.v, self.C, self.F, self.mass, self.vol, self.lam,
                   self.mu, self.grid_mass, self.grid_mom, self.copies_mass, self.copies_mom)


# -- mpm88: Taichi's 88-line weakly compressible fluid, the scene --------------

@njit(parallel=True, cache=True)
def step_mpm88(dt, inv_dx, nx, gravity, bulk, bound, x, v, C, J, mass, vol, grid_mass, grid_mom, copies_mass,
               copies_mom):
    """One step of Taichi's mpm88 (MLS-MPM, quadratic B-splines, pressure stress K (J - 1) folded
    into the affine momentum, J carried as a scalar: J *= 1 + dt tr C), float64; gravity on the
    grid, and walls `bound` nodes thick that stop a node moving out of the grid (as mpm88)."""
    dx = 1.0 / inv_dx
    n = x.shape[0]
    threads = copies_mass.shape[0] + 1
    for t in prange(threads):
        gm, gp = own_zeroed(t, grid_mass, grid_mom, copies_mass, copies_mom)
        for p in range((n * t) // threads, (n * (t + 1)) // threads):
            bx, fx, wx = _bspline(x[p, 0] * inv_dx)
            by, fy, wy = _bspline(x[p, 1] * inv_dx)
            stress = -dt * 4.0 * bulk * vol[p] * (J[p] - 1.0) * inv_dx * inv_dx
            m = mass[p]
            a00, a01 = stress + m * C[p, 0, 0], m * C[p, 0, 1]
            a10, a11 = m * C[p, 1, 0], stress + m * C[p, 1, 1]
            mvx, mvy = m * v[p, 0], m * v[p, 1]
            scatter_affine_2d(dx, nx, bx, fx, wx, by, fy, wy, m, mvx, mvy, a00, a01, a10, a11, gm, gp)
    last = nx - 1 - bound
    for node in prange(grid_mass.shape[0]):
        node_velocity_2d(node, grid_mass, grid_mom, copies_mass, copies_mom)
        grid_mom[node, 1] -= dt * gravity
        ij = (node % nx, node // nx)
        for a in range(2):
            if (ij[a] < bound and grid_mom[node, a] < 0.0) or (ij[a] > last and grid_mom[node, a] > 0.0):
                grid_mom[node, a] = 0.0
    for p in prange(n):
        vx, vy, c00, c01, c10, c11 = gather_2d(dt, inv_dx, nx, x, v, C, grid_mom, p)
        J[p] *= 1.0 + dt * (c00 + c11)


class ReferenceMPM88:
    """Taichi's mpm88 on the particles of a solver scene (unit grid, origin 0), stepped by
    `step_mpm88`."""

    BOUND = 3   # mpm88's wall thickness in nodes

    def __init__(self, x, v, mass, volume, cells: int, bulk: float, gravity: float, threads: int):
        self.x, self.v = x.copy(), v.copy()
        self.mass, self.vol = mass.copy(), volume.copy()
        self.C = np.zeros((x.shape[0], 2, 2))
        self.J = np.ones(x.shape[0])
        self.inv_dx, self.nx = float(cells), cells + 1
        n_nodes = self.nx ** 2
        self.grid_mass, self.grid_mom = np.zeros(n_nodes), np.zeros((n_nodes, 2))
        self.copies_mass = np.zeros((threads - 1, n_nodes))
        self.copies_mom = np.zeros((threads - 1, n_nodes, 2))
        self.bulk, self.gravity = bulk, gravity

    def advance(self, dt: float) -> None:
        step_mpm88(dt, self.inv_dx, self.nx, self.gravity, self.bulk, self.BOUND, self.x, self.v, self.C, self.J,
                   self.mass, self.vol, self.grid_mass, self.grid_mom, self.copies_mass, self.copies_mom)
