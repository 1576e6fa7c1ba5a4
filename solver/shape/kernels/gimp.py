"""GIMP: uGIMP and cpGIMP (review 3.3, eqs. 3.6-3.14; Bardenhagen & Kober 2004).

A particle is a box of side l_p per axis; its weight on node I is the average of
the hat function N_I over the box, phi_I = (1/l_p) int_box N_I (eq. 3.9), the
tensor product over the axes in 2D and 3D. With M_I the antiderivative of N_I
and the box [a, b] along an axis,

    phi_I = (M_I(b) - M_I(a)) / (b - a),
    dphi_I/dx_p = (N_I(b) b' - N_I(a) a' - phi_I (b' - a')) / (b - a),

which is eqs. 3.12-3.13 written piece-free (the same values: the tests check
them against the printed pieces). Three nodes per axis for l_p <= h; the
functions are C1, so the force on a node changes continuously as a particle
crosses a cell face.

uGIMP ("gimp") keeps the initial box, l_p = h / particles_per_cell of the body.
cpGIMP ("cpgimp") stretches it with the diagonal of F, l_p = l_p0 |F_aa|
(eq. 3.14), capped at h where three nodes stop sufficing.

Grid ends: the review adds ghost cells (its Fig. 30). Here the part of a box
beyond a grid end is cut off instead (a = max(x_p - l_p/2, lower), a' = 0 when
cut), so a particle pressed against a wall keeps a partition of unity on the
nodes that exist, at the price of linear reproduction for that particle (its
weights centre on the cut box). A particle whose centre leaves the grid is
reported as outside.
"""
from __future__ import annotations

import numpy as np
from solver.jit import njit, prange

from solver.seeding import box_sides
from solver.shape.kernels import tensor


LENGTH = "domain_length"   # Particles.extra: (n, dim) initial box sides l_p0


def prepare(scene, particles) -> None:
    """Allocate the initial box sides, h / particles_per_cell of each particle's body."""
    if LENGTH in particles.extra:      # restored from a checkpoint
        return
    length = particles.require(LENGTH, (scene.dimension,))
    length[:] = box_sides(scene, particles.body)


def evaluate(spec, x, particles, grid, stencil, blocks) -> int:
    """uGIMP: the initial boxes."""
    return weights(spec, x, particles.extra[LENGTH], grid.lower, grid.inv_h, grid.cells, grid.strides,
                   stencil.idx, stencil.w, stencil.dw, blocks)


def evaluate_contiguous(spec, x, particles, grid, stencil, blocks) -> int:
    """cpGIMP: the boxes stretched along the axes by the diagonal of F."""
    length = stretched(particles.extra[LENGTH], particles.F)
    return weights(spec, x, length, grid.lower, grid.inv_h, grid.cells, grid.strides,
                   stencil.idx, stencil.w, stencil.dw, blocks)


@njit(parallel=True, cache=True)
def stretched(length0, F):
    n, dim = length0.shape
    out = np.empty((n, dim))
    for p in prange(n):   # no scratch, each particle its own row
        for a in range(dim):
            out[p, a] = length0[p, a] * abs(F[p, a, a])
    return out


@njit(cache=True)
def hat_and_integral(y):
    """N(y) = max(0, 1 - |y|) and its antiderivative M(y) = int_-1^y N, in cell units."""
    if y <= -1.0:
        return 0.0, 0.0
    if y <= 0.0:
        return 1.0 + y, 0.5 * (1.0 + y) ** 2
    if y <= 1.0:
        return 1.0 - y, 1.0 - 0.5 * (1.0 - y) ** 2
    return 0.0, 1.0


@njit(cache=True)
def axis(s, a, p, cells, inv_h, length, w1, g1):
    """The three nodes nearest s (in cells) along axis a for the box of side length[p, a]."""
    if not (s >= 0.0 and s <= cells):   # also catches NaN
        return -1
    half = 0.5 * min(max(length[p, a] * inv_h, 1e-12), 1.0)
    lo, hi = s - half, s + half              # the box, cut at the grid ends
    dlo, dhi = 1.0, 1.0
    if lo < 0.0:
        lo, dlo = 0.0, 0.0
    if hi > cells:
        hi, dhi = float(cells), 0.0
    # the three nodes nearest x_p (a box of side <= h touches no other)
    b = min(max(int(s + 0.5) - 1, 0), cells - 2)
    for j in range(3):
        n_hi, m_hi = hat_and_integral(hi - (b + j))
        n_lo, m_lo = hat_and_integral(lo - (b + j))
        phi = (m_hi - m_lo) / (hi - lo)
        w1[a, j] = phi
        g1[a, j] = (n_hi * dhi - n_lo * dlo - phi * (dhi - dlo)) / (hi - lo) * inv_h
    return b


# the 1D function and the declared support (solver/shape/gimp.py), as the tensor kernel takes them
NODES = tensor.nodes_of("gimp")


def weights(spec, x, length, lower, inv_h, cells, strides, idx, w, dw, blocks):
    """The shape-function interface with one more argument: `length` (n, dim), the
    current box sides l_p (capped at h)."""
    kernel = tensor.kernels("gimp").weights   # (generated once: tensor.py)
    return kernel(NODES, spec, x, length, lower, inv_h, cells, strides, idx, w, dw, blocks)
