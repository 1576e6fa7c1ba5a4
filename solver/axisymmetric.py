"""Axisymmetric ULMPM in 2D (review Appendix G): x = r, y = z, theta around the y axis.

What changes against plane strain:

- a particle stands for the ring it sweeps around the axis: its volume and mass
  are the plane ones times 2 pi r (the review's per-radian quantities times 2 pi,
  so masses, energies and forces are those of the whole body and compare
  directly with a 3D run);
- the velocity gradient and the deformation gradient are 3x3, index 2 being
  theta: L_thth = sum_I N_I v_rI / r_p (eq. G.4), F_thth <- (1 + dt L_thth) F_thth,
  so every material sees the hoop rate and stretch as a third principal direction;
- the radial internal force gets the hoop term -V_p sigma_thth N_I / r_p (eq. G.2);
- nodes on the axis r = 0 get v_r = 0 (solver/boundary.py).

r_p in the hoop terms is sum_I N_I r_I, the radius where the weights were
evaluated: for linear (and B-spline) functions it is the particle's radius at
the start of the step, and a velocity v_r = a r gives L_thth = a exactly.
r_I is taken from the node's index in the whole grid, so that a process holding
a slab of it computes the same radii as one process, bit for bit.

Total-Lagrangian MPM (solver/step/formulation.py): neither the review nor the
Karamelo paper writes it out; it is Appendix G's weak form pulled back to the
reference configuration of 2.6 (the hoop component of Grad w is w_r / R, that of
F is r / R). The weights are at X_p, so the radius they give is the reference
radius R_p = sum_I N_I(X_p) R_I, and

- V0_p = 2 pi R_p A_p (the ring of the reference cross-section, as above);
- the hoop component of the deformation gradient is F_thth = r_p / R_p, integrated
  as the in-plane block is: F_dot_thth = sum_I N_I(X_p) v_rI / R_p (the hoop
  component of Grad v), F_thth <- F_thth + dt F_dot_thth, L_thth = F_dot_thth / F_thth;
  V = det(F_rz) F_thth V0;
- the radial internal force gets -V0_p P_thth N_I(X_p) / R_p, with the first
  Piola-Kirchhoff stress's P_thth = J sigma_thth / F_thth (F is block diagonal).

The same kernel adds both formulations' hoop force: the formulation says which
volume and stress (`hoop_measure`), the stencil's weights which radius.
"""
from __future__ import annotations

import numpy as np
from solver.geometry import ring
from solver.jit import njit, prange

from solver.threads import add_node_copies, block_bounds, own


@njit(parallel=True, cache=True)
def add_hoop_force(spec, idx, w, lower_r, h_r, nodes_r, first_r, volume, stress, grid_force, copies_force):
    """f_rI -= V_p sigma_thth,p N_I(x_p) / r_p (the third term of eq. G.2); block t of
    particles adds into copies_force[t - 1] (solver/kernels.py)."""
    n = w.shape[0]
    nodes = spec[1]   # len() taken inside the prange: constants there (solver/kernels.py)
    blocks = copies_force.shape[0] + 1
    bounds = block_bounds(n, blocks)
    for t in prange(blocks):
        nk = len(nodes)
        gf = own(t, grid_force, copies_force)
        for p in range(bounds[t], bounds[t + 1]):
            r = _radius(idx, w, p, nk, lower_r, h_r, nodes_r, first_r)
            s = volume[p] * stress[p, 2, 2] / r
            for k in range(nk):
                gf[idx[p, k], 0] -= w[p, k] * s
    if blocks > 1:
        add_node_copies(grid_force, copies_force)


@njit(parallel=True, cache=True)
def hoop_kinematics(spec, idx, w, lower_r, h_r, nodes_r, first_r, v_grid, dt, L, F, volume):
    """L_thth = sum_I N_I v_rI / r_p (eq. G.4); F_thth and the volume follow."""
    n = w.shape[0]
    nodes = spec[1]
    for p in prange(n):   # no scratch, each particle its own rows
        rate = _hoop_rate(idx, w, p, len(nodes), lower_r, h_r, nodes_r, first_r, v_grid)
        L[p, 2, 2] = rate
        F[p, 2, 2] *= 1.0 + dt * rate
        volume[p] *= 1.0 + dt * rate   # the kinematics kernel took det F with the old F_thth


@njit(parallel=True, cache=True)
def hoop_kinematics_reference(spec, idx, w, lower_r, h_r, nodes_r, first_r, v_grid, dt, L, F, volume):
    """TLMPM: F_dot_thth = sum_I N_I(X_p) v_rI / R_p, F_thth += dt F_dot_thth,
    L_thth = F_dot_thth / F_thth; the volume, det(F_rz) V0 from the in-plane kernel, times F_thth."""
    n = w.shape[0]
    nodes = spec[1]
    for p in prange(n):
        rate = _hoop_rate(idx, w, p, len(nodes), lower_r, h_r, nodes_r, first_r, v_grid)
        F[p, 2, 2] += dt * rate
        L[p, 2, 2] = rate / F[p, 2, 2]
        volume[p] *= F[p, 2, 2]


@njit(cache=True)
def _hoop_rate(idx, w, p, nk, lower_r, h_r, nodes_r, first_r, v_grid):
    """sum_I N_I v_rI / r_p at the weights' position: L_thth (ULMPM), F_dot_thth (TLMPM)."""
    r = _radius(idx, w, p, nk, lower_r, h_r, nodes_r, first_r)
    vr = 0.0
    for k in range(nk):
        vr += w[p, k] * v_grid[idx[p, k], 0]
    return vr / r


@njit(cache=True)
def _radius(idx, w, p, nk, lower_r, h_r, nodes_r, first_r):
    """sum_I N_I(x_p) r_I; nodes are numbered with r fastest, the local grid's first
    r layer being layer first_r of the whole grid (lower_r is the whole grid's)."""
    r = 0.0
    for k in range(nk):
        r += w[p, k] * (lower_r + h_r * (first_r + idx[p, k] % nodes_r))
    return r


@njit(cache=True)
def add_hoop_pressure(idx, w, lower_r, h_r, nodes_r, first_r, volume, pressure, grid_force):
    """f_rI += V_p p_p N_I(x_p) / r_p: a pore pressure's share of the hoop term (the total stress
    is sigma' - p I, sigma_thth = sigma'_thth - p; solver/pore_fluid.py). Serial, as the pore
    fluid's other passes are."""
    nk = idx.shape[1]
    for p in range(idx.shape[0]):
        if pressure[p] == 0.0:   # a dry particle
            continue
        s = volume[p] * pressure[p] / _radius(idx, w, p, nk, lower_r, h_r, nodes_r, first_r)
        for k in range(nk):
            grid_force[idx[p, k], 0] += w[p, k] * s


class Axisymmetry:
    """Turns the plane-strain state of a 2D scene into the axisymmetric one and adds its terms."""

    def __init__(self, scene, particles):
        self._lower_r, self._h_r = float(scene.grid_lower()[0]), float(scene.cell_sizes()[0])
        self._hoop_kinematics = hoop_kinematics_reference if scene.method.formulation == "tlmpm" else hoop_kinematics
        rings = ring(particles.x)
        for name in ("mass", "volume", "volume0"):
            getattr(particles, name)[:] *= rings
        n = particles.count
        F = np.zeros((n, 3, 3))
        F[:, :2, :2] = particles.F
        F[:, 2, 2] = 1.0
        particles.F, particles.L = F, np.zeros((n, 3, 3))

    def place(self, grid, first_r: int) -> None:
        """The grid of this process, whose first node layer along r is layer first_r of the whole grid."""
        self._r = (self._lower_r, self._h_r, int(grid.cells[0]) + 1, first_r)

    # hooks of the step (solver/step/hooks.py)

    def after_forces(self, sim) -> None:
        """The hoop stress's nodal force."""
        s = sim.stencil
        volume, stress = sim.formulation.hoop_measure(sim)   # V_p, sigma_p (ULMPM); V0_p, P_p (TLMPM)
        add_hoop_force(sim.spec, s.idx, s.w, *self._r, volume, stress, sim.grid.force, sim.copies.force)

    def add_pore_pressure_force(self, sim, pressure) -> None:
        """The pore pressure's hoop force (solver/pore_fluid.py calls it with its P2G)."""
        s = sim.stencil
        add_hoop_pressure(s.idx, s.w, *self._r, sim.particles.volume, pressure, sim.grid.force)

    def after_kinematics(self, sim, dt: float, v_grid) -> None:
        """The hoop components of L and F, and the volume with them."""
        s, p = sim.stencil, sim.particles
        self._hoop_kinematics(sim.spec, s.idx, s.w, *self._r, v_grid, dt, p.L, p.F, p.volume)
