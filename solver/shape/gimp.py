"""GIMP: uGIMP and cpGIMP (review 3.3, eqs. 3.10-3.14; Bardenhagen & Kober 2004).

A particle is a box of side l_p per axis; its weight on node I is the average of
the hat function N_I over the box (eq. 3.9). In 1D, with d = (x_p - x_I)/h and
l = l_p / h <= 1 (eq. 3.12):

    phi(d) = 1 - (4 d^2 + l^2) / (4 l)    |d| < l/2
           = 1 - |d|                      l/2 <= |d| <= 1 - l/2
           = (1 + l/2 - |d|)^2 / (2 l)    1 - l/2 < |d| < 1 + l/2
           = 0                            otherwise

three nodes per axis; the tensor product in 2D and 3D. The functions are C1, so
the force on a node changes continuously as a particle crosses a cell face.

uGIMP ("gimp") keeps the initial box, l_p = h / particles_per_cell of the body.
cpGIMP ("cpgimp") stretches it with the diagonal of F, l_p = l_p0 |F_aa|
(eq. 3.14), capped at h where the formula stops being valid.

The grid needs no ghost nodes as long as each particle's box stays inside the
grid: a node beyond the grid end would only get weight from the part of a box
that lies outside. A particle whose box leaves the grid is reported as outside.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from solver.shape.tensor import scatter

SUPPORT = 3
LENGTH = "domain_length"   # Particles.extra: (n, dim) initial box sides l_p0
_TOUCH = 1e-9              # a box may touch the grid end up to round-off (in cells)


def prepare(scene, particles) -> None:
    """Allocate the initial box sides, h / particles_per_cell of each particle's body
    (regular seeding tiles each cell with ppc boxes per axis)."""
    if LENGTH in particles.extra:      # restored from a checkpoint
        return
    length = particles.require(LENGTH, (scene.dimension,))
    ppc = np.array([b.particles_per_cell for b in scene.bodies], dtype=np.float64)
    length[:] = np.asarray(scene.cell_sizes())[None, :] / ppc[particles.body][:, None]


def evaluate(spec, x, particles, grid, stencil) -> int:
    """uGIMP: the initial boxes."""
    return weights(spec, x, particles.extra[LENGTH], grid.lower, grid.inv_h, grid.cells, grid.strides,
                   stencil.idx, stencil.w, stencil.dw)


def evaluate_contiguous(spec, x, particles, grid, stencil) -> int:
    """cpGIMP: the boxes stretched along the axes by the diagonal of F."""
    length = stretched(particles.extra[LENGTH], particles.F, grid.h)
    return weights(spec, x, length, grid.lower, grid.inv_h, grid.cells, grid.strides,
                   stencil.idx, stencil.w, stencil.dw)


@njit(cache=True)
def stretched(length0, F, h):
    n, dim = length0.shape
    out = np.empty((n, dim))
    for p in range(n):
        for a in range(dim):
            out[p, a] = min(length0[p, a] * abs(F[p, a, a]), h[a])
    return out


@njit(cache=True)
def gimp_1d(d, l):
    """(phi, dphi/dd) of eq. 3.12-3.13 in cell units."""
    a = abs(d)
    sign = 1.0 if d >= 0.0 else -1.0
    if a < 0.5 * l:
        return 1.0 - (4.0 * d * d + l * l) / (4.0 * l), -2.0 * d / l
    if a <= 1.0 - 0.5 * l:
        return 1.0 - a, -sign
    if a < 1.0 + 0.5 * l:
        r = 1.0 + 0.5 * l - a
        return r * r / (2.0 * l), -sign * r / l
    return 0.0, 0.0


@njit(cache=True)
def weights(spec, x, length, lower, inv_h, cells, strides, idx, w, dw):
    """The shape-function interface with one more argument: `length` (n, dim), the
    current box sides l_p."""
    n = x.shape[0]
    dim = len(spec[0])
    base = np.empty(dim, dtype=np.int64)
    w1 = np.empty((dim, 3))
    g1 = np.empty((dim, 3))
    for p in range(n):
        for a in range(dim):
            s = (x[p, a] - lower[a]) * inv_h[a]
            l = max(length[p, a] * inv_h[a], 1e-12)
            if not (s - 0.5 * l >= -_TOUCH and s + 0.5 * l <= cells[a] + _TOUCH):   # also catches NaN
                return p
            # the three nodes nearest x_p; at a grid end the one beyond it has weight 0
            b = min(max(int(s + 0.5) - 1, 0), cells[a] - 2)
            base[a] = b
            for j in range(3):
                phi, dphi = gimp_1d(s - (b + j), l)
                w1[a, j] = phi
                g1[a, j] = dphi * inv_h[a]
        scatter(p, 3, base, w1, g1, strides, idx, w, dw)
    return -1
