"""The kernels of total-Lagrangian MPM (review 2.6, Algorithm 3; Karamelo 2.x); the
formulation that feeds them to the phases is solver/step/formulation.py.

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
the one of ULMPM: the kernels only ever see (idx, w, dw). The adaptive
time step is ExplicitMPM's times the smallest principal stretch of any particle
(the reference cells deform with the body). With several processes the slabs
are cut in the reference configuration (solver/parallel/mpi.py): a particle
stays on its process for the whole run, and the ghost sums and halo shares are
those of the updated-Lagrangian step.
"""
from __future__ import annotations

import math

import numpy as np
from solver.jit import njit, prange

from solver import kernels
from solver.threads import block_bounds


# -- kernels ----------------------------------------------------------------------

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
    for p in range(np.uint64(start), np.uint64(stop)):   # unsigned: no wrap-around test (docs/internals.md)
        J = kernels.invert(F[p], Finv)
        for a in range(dim):
            for b in range(dim):
                s = 0.0
                for c in range(dim):
                    s += stress[p, a, c] * Finv[b, c]
                P[p, a, b] = J * s


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
