"""CPDI-R4 (review 3.6.2-3.6.3, eqs. 3.27-3.35; Sadeghirad et al. 2011), in 1D (CPDI-L2,
eq. 3.26), 2D and 3D.

A particle's domain is the box of side l0 = h / particles_per_cell per axis it had
when seeded (the same box as GIMP's, solver/shape/kernels/gimp.py), carried by F:
the parallelogram (parallelepiped) x_p + R xi, xi in [-1, 1]^d, R = F diag(l0 / 2)
(the columns of R are the review's half-length domain vectors r_i, eq. 3.27).
The weight of node I is the mean of the hat function over the domain with the hat
replaced by its interpolant on the corners x_c = x_p + R s_c (s_c in {-1, 1}^d):

    phi_I      = 2^-d sum_c N_I(x_c)                                   (eq. 3.32)
    grad phi_I = sum_c N_I(x_c) g_c,  g_c = 2^-d R^-T s_c              (eq. 3.32)

g_c is the mean over the domain of the gradient of the corner's multilinear
function (the review's 2D expression written for any d: the affine map makes the
mean of d/dxi_a of prod_b (1 + s_cb xi_b) / 2 equal to s_ca / 2^d). The weights
sum to 1 and the gradients to 0 (eq. 3.33); a linear field's gradient is
reproduced exactly.

The stencil is the 4 nodes per axis from the node below the particle's cell
(cells i-1, i, i+1 around the particle's cell i, nearer the grid ends shifted
inwards): corners up to one cell either side. A corner beyond that (a domain
stretched over more than the three cells, where CPDI develops the holes of
review 3.7 / spec E28) stops the run naming the particle: `failure` tells it
apart from a particle outside the grid. A corner beyond a grid end is moved onto
it (review 3.7: "GIMP/CPDI need ghost cells"; here, as GIMP's boxes are cut), so
the weights keep their partition of unity at walls, at the price of linear
reproduction for that particle.
"""
from __future__ import annotations

import numpy as np
from numba import njit, prange

from solver.shape.kernels.gimp import LENGTH, prepare  # noqa: F401  (the seeded boxes: the domains at t = 0)
from solver.kernels import invert
from solver.threads import block_bounds, first_of

SUPPORT = 4
SPANS = 1   # kinds of failure: the particle's own cell is outside the grid (0) or a corner is too far (1)


def evaluate(spec, x, particles, grid, stencil, blocks) -> int:
    return weights(spec, x, particles.extra[LENGTH], particles.F, grid.lower, grid.inv_h, grid.cells, grid.strides,
                   stencil.idx, stencil.w, stencil.dw, blocks)


def failure(x, particles, grid, index):
    """(quantity, detail) for a particle the weights refused whose centre is inside the
    grid (its domain is too large), None for one outside the grid."""
    s = (x[index] - grid.lower) * grid.inv_h
    if not np.all((s >= 0) & (s <= grid.cells)):
        return None
    corners = domain_corners(x[index:index + 1], particles.extra[LENGTH][index:index + 1],
                             particles.F[index:index + 1])[0]
    extent = (corners.max(axis=0) - corners.min(axis=0)) * grid.inv_h
    return ("particle domain (cpdi_r4)",
            f"spans {np.array2string(extent, precision=3)} cells per axis and reaches beyond the cells next to "
            "its own, which its stencil covers (larger domains leave holes in CPDI's weights, review 3.7): a "
            "domain is h / particles_per_cell stretched by F, so seed more particles per cell, or use a shape "
            "function without domains ('gimp', 'cubic_bspline')")


def domain_corners(x, length, F) -> np.ndarray:
    """(n, 2^d, d): the corners x_p + F diag(l0/2) s_c, s_c in {-1, 1}^d with axis 0 fastest
    (2D: the review's x1, x2, x4, x3; the `particle_domain` output field)."""
    n, d = x.shape
    signs = np.array([[1.0 if (c >> a) & 1 else -1.0 for a in range(d)] for c in range(2 ** d)])
    R = F[:, :d, :d] * (0.5 * length)[:, None, :]
    return x[:, None, :] + np.einsum("pab,cb->pca", R, signs)


@njit(parallel=True, cache=True)
def weights(spec, x, length, F, lower, inv_h, cells, strides, idx, w, dw, blocks):
    dims, nodes = spec
    if SUPPORT ** len(dims) != len(nodes):
        raise ValueError("cpdi_r4: the stencil is not 4 nodes per axis")
    bounds = block_bounds(x.shape[0], blocks)
    bad = np.empty(blocks, dtype=np.int64)
    for t in prange(blocks):
        bad[t] = _block(dims, nodes, bounds[t], bounds[t + 1], x, length, F, lower, inv_h, cells, strides,
                        idx, w, dw)
    return first_of(bad)


@njit(cache=True)
def _block(dims, nodes, start, stop, x, length, F, lower, inv_h, cells, strides, idx, w, dw):
    dim, nk = len(dims), len(nodes)
    corners = 2 ** dim
    base = np.empty(dim, dtype=np.int64)
    R = np.empty((dim, dim))        # the half-length domain vectors as columns, in cell units
    Rinv = np.empty((dim, dim))
    first = np.empty(dim, dtype=np.int64)
    w1 = np.empty((dim, 2))
    for p in range(start, stop):
        for a in range(dim):
            s = (x[p, a] - lower[a]) * inv_h[a]
            if not (s >= 0.0 and s <= cells[a]):   # also catches NaN
                return p
            base[a] = min(max(min(int(s), cells[a] - 1) - 1, 0), cells[a] - 3)
        for a in range(dim):
            for b in range(dim):
                R[a, b] = F[p, a, b] * 0.5 * length[p, b] * inv_h[a]
        if invert(R, Rinv) <= 0.0:   # an inverted domain (the step reports its J)
            return p
        for k in range(nk):
            w[p, k] = 0.0
            for a in range(dim):
                dw[p, k, a] = 0.0
        for c in range(corners):
            for a in range(dim):   # the corner's cell and its hat weights, the corner moved onto the grid
                s = (x[p, a] - lower[a]) * inv_h[a]
                for b in range(dim):
                    s += R[a, b] * (1.0 if (c >> b) & 1 else -1.0)
                s = min(max(s, 0.0), float(cells[a]))
                i = min(int(s), cells[a] - 1)
                if i < base[a] or i > base[a] + 2:
                    return p
                first[a] = i - base[a]
                w1[a, 1] = s - i
                w1[a, 0] = 1.0 - w1[a, 1]
            _add_corner(c, dim, first, w1, Rinv, inv_h, corners, p, w, dw)
        for k in range(nk):
            node = 0
            rest = k
            for a in range(dim):
                node += (base[a] + rest % SUPPORT) * strides[a]
                rest //= SUPPORT
            idx[p, k] = node
    return -1


@njit(cache=True)
def _add_corner(c, dim, first, w1, Rinv, inv_h, corners, p, w, dw):
    """The hat weights N_I(x_c) of corner c on its cell's 2^d nodes, into phi_I and grad phi_I."""
    for j in range(corners):
        k = 0
        stride = 1
        N = 1.0
        for a in range(dim):
            bit = (j >> a) & 1
            k += (first[a] + bit) * stride
            stride *= SUPPORT
            N *= w1[a, bit]
        w[p, k] += N / corners
        for a in range(dim):      # g_c = 2^-d R^-T s_c, R in cells: d/dx_a = inv_h[a] d/ds_a
            g = 0.0
            for b in range(dim):
                g += Rinv[b, a] * (1.0 if (c >> b) & 1 else -1.0)
            dw[p, k, a] += N * g * inv_h[a] / corners
