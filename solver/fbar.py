"""F-bar: the cell-averaged Jacobian of review 5.2, Algorithm 7 (`"method": {"fbar": true}`).

Low-order MPM locks when the material is nearly incompressible: every particle
must keep its own volume, more constraints than the grid has velocities, and the
pressure checkerboards. F-bar lets each cell keep one volume instead: for the
stress update only, every particle's F, V and L are replaced by

    J_c      = sum_p V0_p J_p / sum_p V0_p      over the particles p in cell c (eq. 5.17)
    F_bar    = (J_c / J_p)^(1/d) F_p            (eq. 5.15; d the size of F: 2 in plane
                                                 strain, 3 in 3D and axisymmetry)
    V_bar    = J_c V0_p
    L_bar    = L_p + (1/d) d/dt ln(J_c / J_p) I  (the velocity gradient of F_bar, so the
                                                 rate models get the same volume change)

and the true ones are put back after it, so the internal force, the energies and
the next step see the particles' own kinematics. The rate of ln(J_c / J_p) needs
its value at the last stress update: kept per particle as `extra["fbar_log_ratio"]`
(migrates and checkpoints with the particle).

The cell sums are nodal arrays at each cell's lower-corner node, so the halo of
solver/parallel sums them across slab boundaries (sum_ghosts to the owners,
share_nodes back) as it does the grid's mass. The positions are those the
formulation's weights use: x_p (ULMPM) or X_p (TLMPM, whose cells never change).
Massless particles (rigid bodies) neither count nor change.
"""
from __future__ import annotations

import numpy as np
from solver.jit import njit, prange

from solver.threads import block_bounds

LOG_RATIO = "fbar_log_ratio"


@njit(cache=True)
def cell_sums(x, lower, inv_h, cells, strides, offset, mass, volume, volume0, cell, vol0_cell, vol_cell):
    """Algorithm 7, lines 1-6: each particle's cell (its lower-corner node on this
    process's grid, or -1 for a massless one) and the cells' V0 and V sums. Serial:
    particles of one cell add into the same entry (one add per particle)."""
    n, dim = x.shape[0], x.shape[1]
    for p in range(n):
        if mass[p] == 0.0:
            cell[p] = -1
            continue
        node = -offset
        for a in range(dim):
            c = int(np.floor((x[p, a] - lower[a]) * inv_h[a]))
            c = min(max(c, 0), cells[a] - 1)
            node += c * strides[a]
        cell[p] = node
        vol0_cell[node] += volume0[p]
        vol_cell[node] += volume[p]


@njit(parallel=True, cache=True)
def apply_fbar(cell, vol0_cell, vol_cell, dt, F, L, volume, volume0, log_ratio, blocks):
    """Algorithm 7, lines 7-12, and the volume and velocity gradient that go with F_bar,
    one block of particles per thread (solver/threads.py)."""
    bounds = block_bounds(F.shape[0], blocks)
    for t in prange(blocks):
        _apply_block(bounds[t], bounds[t + 1], cell, vol0_cell, vol_cell, dt, F, L, volume, volume0, log_ratio)


@njit(cache=True)
def _apply_block(start, stop, cell, vol0_cell, vol_cell, dt, F, L, volume, volume0, log_ratio):
    d = F.shape[1]
    for p in range(start, stop):
        node = cell[p]
        if node < 0:
            continue
        J_cell = vol_cell[node] / vol0_cell[node]
        r = np.log(J_cell * volume0[p] / volume[p])     # ln(J_c / J_p)
        scale = np.exp(r / d)
        rate = (r - log_ratio[p]) / (d * dt)
        log_ratio[p] = r
        for a in range(d):
            L[p, a, a] += rate
            for b in range(d):
                F[p, a, b] *= scale
        volume[p] = J_cell * volume0[p]


class FBar:
    """The hook (solver/step/hooks.py): F_bar, V_bar, L_bar for the stress update, the
    particles' own F, V, L after it."""

    def __init__(self, sim):
        n_nodes = sim.grid.n_nodes
        self._vol0_cell = np.zeros(n_nodes)
        self._vol_cell = np.zeros(n_nodes)
        self._saved = None
        sim.particles.require(LOG_RATIO)

    def after_kinematics(self, sim, dt: float, v_grid) -> None:
        p, f = sim.particles, sim.frame
        if self._saved is None or len(self._saved[0]) != p.count:   # (particles migrated)
            self._saved = (np.empty_like(p.F), np.empty_like(p.L), np.empty_like(p.volume),
                           np.empty(p.count, dtype=np.int64))
        F, L, volume, cell = self._saved
        np.copyto(F, p.F)
        np.copyto(L, p.L)
        np.copyto(volume, p.volume)
        self._vol0_cell.fill(0.0)
        self._vol_cell.fill(0.0)
        cell_sums(sim.formulation.positions(p), f.lower, f.inv_h, f.cells, f.strides, f.offset, p.mass, p.volume,
                  p.volume0, cell, self._vol0_cell, self._vol_cell)
        sim.domain.sum_ghosts(self._vol0_cell, self._vol_cell)    # cells across slab boundaries
        sim.domain.share_nodes(self._vol0_cell, self._vol_cell)
        apply_fbar(cell, self._vol0_cell, self._vol_cell, dt, p.F, p.L, p.volume, p.volume0, p.extra[LOG_RATIO],
                   sim.threads)

    def after_stress(self, sim, dt: float) -> None:
        p = sim.particles
        F, L, volume, _ = self._saved
        np.copyto(p.F, F)
        np.copyto(p.L, L)
        np.copyto(p.volume, volume)
