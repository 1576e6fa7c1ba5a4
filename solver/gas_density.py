"""A gas's density from the grid (`ideal_gas` `density_from_grid`).

A gas expands to about one particle per cell (Sod's left plateau: 1.3 of the 3 it started
with). With linear hats the particles' volumes, V_p = J_p V0_p, then drift away from the
room the particles take: the velocity gradient of a cell holding one particle is a poor
estimate of its own expansion, and the volumes of Sod's rarefaction came about twice the
particles' spacing (plateau pressure 54 % low at cfl 0.5). So at the start of each step a
gas particle takes the density of the grid where it is:

    rho_I = m_I / V_I,    m_I = sum_p N_I(x_p) m_p over the gas particles,
    V_I = integral of N_I over the grid (h^d inside; less at the grid's ends),
    rho_p = sum_I N_I(x_p) rho_I,    V_p = m_p / rho_p,

at the positions the last step moved the particles to (after they migrated to their
process's slab). Particles that tile the room they take, with the masses they were seeded
with, keep their volumes (to the shape functions' quadrature error). The reset is reversible
work on the gas: its internal energy follows the adiabat, e_new = e (V_p / V_new)^(gamma - 1),
the pressure in the stress moves with it, and F_p is scaled to J = V / V0. The energy it
moves is booked as `gas_density_work` (solver/energy.py).

It assumes the gas fills the cells it is in: at a free surface or beside another material
the surface nodes hold less gas than their volume, and the gas there is too light. The
integrals V_I need weights that depend on the position alone (not GIMP's or CPDI's
per-particle domains), ULMPM and a plane grid (not axisymmetric);
solver/materials/ideal_gas.py `grid_density_refusal` says why not where they do not hold.
"""
from __future__ import annotations

import math
from functools import reduce
from types import SimpleNamespace

import numpy as np

from solver import kernels
from solver.jit import njit
from solver.materials.ideal_gas import takes_grid_density
from solver.state import Stencil, make_stencil

NAME = "gas_density_work"
_GAUSS = ((-math.sqrt(0.6), 5.0 / 9.0), (0.0, 8.0 / 9.0), (math.sqrt(0.6), 5.0 / 9.0))   # on [-1, 1]


def make(sim):
    """The hook of a scene with a gas that takes its density from the grid, else None."""
    scene = sim.scene
    names = {name for name, material in scene.materials.items() if takes_grid_density(scene, material)}
    return GridDensity(sim, names) if names else None


class GridDensity:
    """The hook (solver/step/hooks.py): the gases' volumes from the grid before each step."""

    def __init__(self, sim, names: set[str]):
        self._models = {id(sim.material_model(name)) for name in names}
        self._volume = nodal_volumes(sim)
        self._mass = np.zeros(sim.grid.n_nodes)
        self._stencil = None

    def begin_step(self, sim, t_end: float) -> None:
        """At the step's start, where every particle is inside its process's grid (after the
        last step's migration): the last stress update's volumes, taken at the positions they
        ended the step at."""
        p = sim.particles
        gases = [(model, sl) for model, sl in sim.materials if id(model) in self._models]
        if self._stencil is None or self._stencil.w.shape[0] != p.count:   # (particles migrated)
            self._stencil = make_stencil(p.count, p.dimension, sim.wide_support)
        stencil = self._stencil
        self._mass.fill(0.0)
        for _, sl in gases:   # (the weights of the gas's particles only: a solid beside it needs none)
            rows = Stencil(stencil.idx[sl], stencil.w[sl], stencil.dw[sl])
            sim.domain.weights(sim.shape, sim.wide_spec, p.x[sl], p, sim.grid, rows)
            scatter_mass(rows.idx, rows.w, p.mass[sl], self._mass)
        sim.domain.sum_ghosts(self._mass)
        sim.domain.share_nodes(self._mass)
        density = np.divide(self._mass, self._volume, out=np.zeros_like(self._mass), where=self._volume > 0)
        moved = 0.0
        for model, sl in gases:
            moved += take_grid_density(stencil.idx[sl], stencil.w[sl], density, model.gamma, p.mass[sl],
                                       p.volume[sl], p.F[sl], p.extra["internal_energy"][sl], p.stress[sl])
        sim.work.add(NAME, moved)


def nodal_volumes(sim) -> np.ndarray:
    """V_I = the integral of N_I over the grid, for the nodes of this process's grid (one
    field): the product of each axis's 1D integrals, taken by 3-point Gauss rules on each
    half cell, exact for polynomials of degree up to 5 between the functions' knots."""
    grid, dim = sim.grid, sim.scene.dimension
    whole_cells = np.asarray(sim.scene.grid_shape(), dtype=np.int64)
    whole_lower = np.asarray(sim.scene.grid_lower(), dtype=np.float64)
    per_axis = []
    for a in range(dim):
        v = axis_integrals(sim.shape, sim.wide_support, float(whole_lower[a]), float(grid.h[a]), int(whole_cells[a]))
        first = sim.domain.first_node(a)
        per_axis.append(v[first:first + int(grid.cells[a]) + 1])
    # nodes are numbered axis 0 fastest: the outer product from the last axis to the first
    return np.ascontiguousarray(reduce(np.multiply.outer, reversed(per_axis)).ravel())


def axis_integrals(module, support: int, lower: float, h: float, cells: int) -> np.ndarray:
    """The integrals of the 1D functions of nodes 0 .. cells over the part of
    [lower, lower + cells h] where a particle may be (quadratic B-splines refuse the half
    cell at each end, where a particle's stencil would need a node beyond the grid)."""
    half = 0.5 * h   # the pieces of quadratic B-splines meet at the cells' middles, the others' at nodes
    centre = lower + half * (np.arange(2 * cells) + 0.5)
    x = np.concatenate([centre + 0.5 * half * s for s, _ in _GAUSS])[:, None]
    weight = np.repeat([0.5 * half * g for _, g in _GAUSS], 2 * cells)
    n, spec = x.shape[0], kernels.stencil_spec(1, support)
    line = SimpleNamespace(lower=np.array([lower]), inv_h=np.array([1.0 / h]), cells=np.array([cells], np.int64),
                           strides=np.array([1], np.int64))   # one axis of the grid, as the kernels take a grid
    idx, w, dw = np.zeros((n, support), dtype=np.int64), np.zeros((n, support)), np.zeros((n, support, 1))
    start = 0
    while start < n:   # a refused point stops the kernel: take it out and go on after it
        refused = module.weights(spec, x[start:], line.lower, line.inv_h, line.cells, line.strides,
                                 idx[start:], w[start:], dw[start:], 1)
        if refused < 0:
            break
        weight[start + refused] = 0.0
        w[start + refused] = 0.0
        start += refused + 1
    return np.bincount(idx.ravel(), (w * weight[:, None]).ravel(), minlength=cells + 1)


@njit(cache=True)
def scatter_mass(idx, w, mass, out):
    for p in range(idx.shape[0]):
        for k in range(idx.shape[1]):
            out[idx[p, k]] += w[p, k] * mass[p]


@njit(cache=True)
def take_grid_density(idx, w, density, gamma, mass, volume, F, energy, stress):
    """Each particle's volume m / rho(x_p), its internal energy along the adiabat, the
    pressure of its stress and its F with it; returns the internal energy the gas gained."""
    dim = F.shape[1]
    gained = 0.0
    for p in range(idx.shape[0]):
        rho = 0.0
        for k in range(idx.shape[1]):
            rho += w[p, k] * density[idx[p, k]]
        if not rho > 0.0:
            continue
        ratio = mass[p] / (rho * volume[p])            # V_new / V_old
        e = energy[p] * ratio ** (1.0 - gamma)
        gained += mass[p] * (e - energy[p])
        change = (gamma - 1.0) * (rho * e - mass[p] / volume[p] * energy[p])   # p_new - p_old
        energy[p] = e
        volume[p] = mass[p] / rho
        for a in range(3):
            stress[p, a, a] -= change
        scale = ratio if dim == 1 else (math.sqrt(ratio) if dim == 2 else np.cbrt(ratio))   # ratio^(1/dim)
        for a in range(dim):
            for b in range(dim):
                F[p, a, b] *= scale
    return gained
