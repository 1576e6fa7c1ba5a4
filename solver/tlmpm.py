"""The explicit total-Lagrangian MPM step (review 2.6, Algorithm 3; Karamelo 2.x).

TLMPM writes the momentum balance in the reference configuration:

- the shape functions phi_I(X_p) and their reference gradients grad0 phi_I(X_p)
  are computed once, at the particles' reference positions X_p, and so is the
  nodal mass m_I (the grid covers the reference configuration only);
- the internal force is f_I = -sum_p V_p^0 P_p grad0 phi_I with the first
  Piola-Kirchhoff stress P = J sigma F^-T (review Table 4);
- F is integrated from its rate, F_dot = sum_I v_I (x) grad0 phi_I (eq. 2.67),
  and the materials get L = F_dot F^-1, so they compute Cauchy stress from F
  (neo-Hookean) or from L (hypoelastic) exactly as in the updated-Lagrangian step.

Particles never change cells in the reference configuration, so there is no
cell-crossing noise and no particle ever leaves the grid; x_p is still advanced
for output and for body forces written in x, y, z. There is no inherent contact
between bodies (review 2.6).

Everything else (grid update, boundary conditions, PIC/FLIP/APIC, energies) is
the one of `ExplicitMPM`: the kernels only ever see (idx, w, dw). The adaptive
time step is ExplicitMPM's times the smallest principal stretch of any particle
(the reference cells deform with the body). With several processes the slabs
are cut in the reference configuration (solver/parallel/mpi.py): a particle
stays on its process for the whole run, and the ghost sums and halo shares are
those of the updated-Lagrangian step.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from solver import kernels
from solver.stepper import ExplicitMPM
from solver.threads import block_bounds, first_of


class TotalLagrangianMPM(ExplicitMPM):
    """Particles, grid and the total-Lagrangian step of one scene."""

    # -- the step (Algorithm 3; USL and USF differ from MUSL as in ULMPM) --------

    def _step_musl(self, dt: float) -> None:
        p, g, s, c, halo = self.particles, self.grid, self.stencil, self.copies, self.domain
        g.reset()     # m_I comes out the same every step: the weights are fixed (F18)
        acc = self._acceleration = self.loads.acceleration(p, self.time)
        first_piola(p.F, p.stress, self.piola, self.threads)            # P = J sigma F^-T
        kernels.p2g(self.spec, s.idx, s.w, s.dw, p.mass, p.v, p.volume0, self.piola, acc,
                    g.mass, g.momentum, g.force, c.mass, c.momentum, c.force)   # lines 9-12: (mv)_I, f_I with V0, P
        self._affine_p2g()
        halo.sum_ghosts(g.mass, g.momentum, g.force)                    # (processes: ghost nodes to owners)
        kernels.integrate_nodes(dt, g.mass, g.momentum, g.force,
                                self.mass_cutoff, g.v_old, g.v_new)     # lines 14, 17
        self._impose(g.v_old)                                           # line 15
        self.boundary_work += self._impose(g.v_new, record=True)
        halo.share_nodes(g.v_old, g.v_new)                              # (owners' values to ghost nodes)
        g.momentum.fill(0.0)
        self._affine_g2p(g.v_new, True)
        kernels.g2p(self.spec, s.idx, s.w, dt, self.flip_ratio, g.v_old, g.v_new,
                    p.x, p.v, p.mass, True, g.momentum, c.momentum)     # lines 18-19, 28: v_p, (mv)_I, x_p
        halo.sum_ghosts(g.momentum)
        kernels.nodal_velocity(g.mass, g.momentum, g.v_new)
        self._impose(g.v_new)                                           # line 20
        halo.share_nodes(g.v_new)
        self._update_stress(dt, g.v_new)                                # lines 23-27: F_dot, F, L, sigma

    def _step_usl(self, dt: float) -> None:
        p, g, s, c, halo = self.particles, self.grid, self.stencil, self.copies, self.domain
        g.reset()
        acc = self._acceleration = self.loads.acceleration(p, self.time)
        first_piola(p.F, p.stress, self.piola, self.threads)
        kernels.p2g(self.spec, s.idx, s.w, s.dw, p.mass, p.v, p.volume0, self.piola, acc,
                    g.mass, g.momentum, g.force, c.mass, c.momentum, c.force)
        self._affine_p2g()
        halo.sum_ghosts(g.mass, g.momentum, g.force)
        kernels.integrate_nodes(dt, g.mass, g.momentum, g.force, self.mass_cutoff, g.v_old, g.v_new)
        self._impose(g.v_old)
        self.boundary_work += self._impose(g.v_new, record=True)
        halo.share_nodes(g.v_old, g.v_new)
        self._affine_g2p(g.v_new, False)
        kernels.g2p(self.spec, s.idx, s.w, dt, self.flip_ratio, g.v_old, g.v_new,
                    p.x, p.v, p.mass, False, g.momentum, c.momentum)
        self._update_stress(dt, g.v_new)                                # from v~_I^{t+dt}

    def _step_usf(self, dt: float) -> None:
        p, g, s, c, halo = self.particles, self.grid, self.stencil, self.copies, self.domain
        g.reset()
        kernels.p2g_mass_momentum(self.spec, s.idx, s.w, p.mass, p.v, g.mass, g.momentum, c.mass, c.momentum)
        self._affine_p2g()
        halo.sum_ghosts(g.mass, g.momentum)
        kernels.nodal_velocity(g.mass, g.momentum, g.v_old)
        self._impose(g.v_old)
        halo.share_nodes(g.v_old)
        self._update_stress(dt, g.v_old)                                # stress first, from v_I^t
        acc = self._acceleration = self.loads.acceleration(p, self.time)
        first_piola(p.F, p.stress, self.piola, self.threads)
        kernels.p2g_force(self.spec, s.idx, s.w, s.dw, p.mass, p.volume0, self.piola, acc, g.force, c.force)
        halo.sum_ghosts(g.force)
        kernels.integrate_nodes(dt, g.mass, g.momentum, g.force, self.mass_cutoff, g.v_old, g.v_new)
        self._impose(g.v_old)
        self.boundary_work += self._impose(g.v_new, record=True)
        halo.share_nodes(g.v_old, g.v_new)
        self._affine_g2p(g.v_new, False)
        kernels.g2p(self.spec, s.idx, s.w, dt, self.flip_ratio, g.v_old, g.v_new,
                    p.x, p.v, p.mass, False, g.momentum, c.momentum)

    # -- phases -----------------------------------------------------------------

    def place(self) -> None:
        """The grid and the reference weights (Alg. 3 lines 3-4): once at the start, and
        again for a new stencil (a restart)."""
        super().place()
        self._reference_weights()

    def _place_particles(self) -> None:
        super()._place_particles()
        p = self.particles
        self.piola = np.zeros((p.count, self.scene.dimension, self.scene.dimension))

    def _reference_weights(self) -> None:
        """phi_I(X_p) and grad0 phi_I(X_p): the stencil never changes afterwards."""
        p, g, s = self.particles, self.grid, self.stencil
        outside = self.domain.weights(self.shape, self.spec, p.X, p, g, s)   # node numbers of this process's grid
        if outside >= 0:
            self._fail(outside, "reference position", "lies outside the grid")

    def stable_time_step(self, cfl: float) -> float:
        """The updated-Lagrangian step times the smallest principal stretch of any particle
        (at most 1). The reference cells deform with the body: a cell squashed to lambda h
        is crossed by a wave in lambda h / c, so the fixed h of the reference grid overstates
        the stable step where the body is compressed (the impact face of a Taylor bar,
        flattened to a fifth, went unstable at the reference step). Karamelo's TLMPM scales
        its step the same way."""
        stretch = self.domain.min(smallest_stretch(self.particles.F))
        return super().stable_time_step(cfl) * min(stretch, 1.0)

    # APIC in the reference configuration: C_p is the affine velocity field in X,
    # v(X) = v_p + C_p (X - X_p), the weights having been evaluated at X_p.

    def _affine_p2g(self) -> None:
        if self.affine is not None:
            self.affine.p2g(self.spec, self.stencil, self.particles, self.particles.X, self.grid.momentum,
                            self.copies.momentum)

    def _affine_g2p(self, v_grid: np.ndarray, double_map: bool) -> None:
        if self.affine is not None:
            self.affine.g2p(self.spec, self.stencil, self.particles, self.particles.X, v_grid, double_map,
                            self.grid.momentum, self.copies.momentum)

    def _update_stress(self, dt: float, v_grid: np.ndarray) -> None:
        p, s = self.particles, self.stencil
        inverted = update_deformation(self.spec, s.idx, s.dw, v_grid, dt, p.F, p.L, p.volume, p.volume0,
                                      self.threads)
        if inverted >= 0:
            J = float(np.linalg.det(p.F[inverted]))
            self._fail(inverted, "J = det F", f"{J:.6g} <= 0 (the material point has inverted)")
        for material, sl in self.materials:
            material.update_stress(p, sl, dt)


# -- kernels ----------------------------------------------------------------------

@njit(cache=True)
def invert(A, out):
    """out = A^-1 for a 1x1, 2x2 or 3x3 matrix; returns det A (out is garbage when it is 0)."""
    dim = A.shape[0]
    det = kernels.determinant(A)
    r = 1.0 / det if det != 0.0 else 0.0
    if dim == 1:
        out[0, 0] = r
    elif dim == 2:
        out[0, 0] = A[1, 1] * r
        out[0, 1] = -A[0, 1] * r
        out[1, 0] = -A[1, 0] * r
        out[1, 1] = A[0, 0] * r
    else:
        for i in range(3):
            for j in range(3):
                # cofactor of A[j, i]: the cyclic indices avoid the sign bookkeeping
                j1, j2 = (j + 1) % 3, (j + 2) % 3
                i1, i2 = (i + 1) % 3, (i + 2) % 3
                out[i, j] = (A[j1, i1] * A[j2, i2] - A[j1, i2] * A[j2, i1]) * r
    return det


@njit(parallel=True, cache=True)
def first_piola(F, stress, P, blocks):
    """P = J sigma F^-T (review Table 4) on the in-plane block.

    In plane strain F_zz = 1 and F^-T has no zz coupling with the plane, so the
    in-plane block of P needs only the in-plane blocks of sigma and F.
    """
    bounds = block_bounds(F.shape[0], blocks)
    for t in prange(blocks):
        _piola_block(bounds[t], bounds[t + 1], F, stress, P)


@njit(cache=True)
def _piola_block(start, stop, F, stress, P):
    dim = F.shape[1]
    Finv = np.empty((dim, dim))   # allocated per block (solver/kernels.py)
    for p in range(start, stop):
        J = invert(F[p], Finv)
        for a in range(dim):
            for b in range(dim):
                s = 0.0
                for c in range(dim):
                    s += stress[p, a, c] * Finv[b, c]
                P[p, a, b] = J * s


@njit(parallel=True, cache=True)
def update_deformation(spec, idx, dw0, v_grid, dt, F, L, volume, volume0, blocks):
    """F_dot = sum_I v_I (x) grad0 phi_I, F <- F + dt F_dot, L = F_dot F^-1, V = J V0
    (Algorithm 3, lines 23-25).

    Returns the index of the first particle whose J = det F is not positive, or -1.
    """
    dims, nodes = spec
    bounds = block_bounds(idx.shape[0], blocks)
    bad = np.empty(blocks, dtype=np.int64)
    for t in prange(blocks):
        bad[t] = _deformation_block(dims, nodes, bounds[t], bounds[t + 1], idx, dw0, v_grid, dt, F, L, volume, volume0)
    return first_of(bad)


@njit(cache=True)
def _deformation_block(dims, nodes, start, stop, idx, dw0, v_grid, dt, F, L, volume, volume0):
    dim, nk = len(dims), len(nodes)
    Fdot = np.empty((dim, dim))
    Finv = np.empty((dim, dim))
    bad = -1
    for p in range(start, stop):
        Fdot[:, :] = 0.0
        for k in range(nk):
            node = idx[p, k]
            for a in range(dim):
                va = v_grid[node, a]
                for b in range(dim):
                    Fdot[a, b] += va * dw0[p, k, b]
        for a in range(dim):
            for b in range(dim):
                F[p, a, b] += dt * Fdot[a, b]
        J = invert(F[p], Finv)
        for a in range(dim):
            for b in range(dim):
                s = 0.0
                for c in range(dim):
                    s += Fdot[a, c] * Finv[c, b]
                L[p, a, b] = s
        volume[p] = J * volume0[p]
        if J <= 0.0 and bad < 0:
            bad = p
    return bad


@njit(cache=True)
def smallest_stretch(F):
    """min over particles of the smallest principal stretch, sqrt(smallest eigenvalue of F^T F)
    (closed form: 1D |F|, 2D the quadratic, 3D the trigonometric solution of the cubic)."""
    n, dim = F.shape[0], F.shape[1]
    C = np.empty((dim, dim))
    smallest = math.inf
    for p in range(n):
        for a in range(dim):
            for b in range(dim):
                c = 0.0
                for k in range(dim):
                    c += F[p, k, a] * F[p, k, b]
                C[a, b] = c
        if dim == 1:
            lam = C[0, 0]
        elif dim == 2:
            half = 0.5 * (C[0, 0] - C[1, 1])
            lam = 0.5 * (C[0, 0] + C[1, 1]) - math.sqrt(half * half + C[0, 1] * C[0, 1])
        else:
            off = C[0, 1] * C[0, 1] + C[0, 2] * C[0, 2] + C[1, 2] * C[1, 2]
            q = (C[0, 0] + C[1, 1] + C[2, 2]) / 3.0
            a0, a1, a2 = C[0, 0] - q, C[1, 1] - q, C[2, 2] - q
            spread = math.sqrt((a0 * a0 + a1 * a1 + a2 * a2 + 2.0 * off) / 6.0)
            if spread == 0.0:
                lam = q
            else:
                # det of B = (C - q I) / spread, halved: cos(3 phi), clamped against round-off
                r = (a0 * (a1 * a2 - C[1, 2] * C[1, 2]) - C[0, 1] * (C[0, 1] * a2 - C[1, 2] * C[0, 2])
                     + C[0, 2] * (C[0, 1] * C[1, 2] - a1 * C[0, 2])) / (2.0 * spread ** 3)
                phi = math.acos(min(max(r, -1.0), 1.0)) / 3.0
                lam = q + 2.0 * spread * math.cos(phi + 2.0 * math.pi / 3.0)
        stretch = math.sqrt(max(lam, 0.0))
        if stretch < smallest:
            smallest = stretch
    return smallest
