"""Saturated soil: the pore pressure of a material's `pore_fluid` (single-point u-p MPM).

Formulation (docs/scene.md, "pore_fluid"): one set of particles carries the mixture;
the mixture's momentum takes the total stress sigma = sigma' - p I (tension positive,
p positive in compression), the material's model updates the effective stress sigma'
as it would a dry one, and the fluid's acceleration relative to the skeleton is
neglected (Zienkiewicz's u-p form, valid well below the frequency k-dependent limit).
The pore pressure of each particle follows the fluid's mass balance with Darcy's law,

    (n / K_w) dp/dt = -div v_s - div q,     q = -(k / (rho_w g_n)) (grad p - rho_w g),

split into two explicit parts a step:
- the skeleton's volume change, from the L_p the stress update used (after_stress), in the
  weak form on the grid, S_I dp_I = -dt sum_p phi_I V_p tr(L_p), so that the undrained
  response holds: an instant load is carried by p and sigma' in the ratio of K_w / n to the
  skeleton's constrained modulus (taken at the particle, p += -(K_w/n) tr(L_p) dt, the
  cell-constant tr(L_p) of linear hats would leave a saw-tooth in p that the flow's nodal
  changes never see);
- the flow, on the grid (after_forces, with p^t): the storage-weighted nodal pressure
  p_I = sum_p phi_I V_p (n/K_w) p_p / S_I, held on the drained nodes (the `pore_pressure`
  conditions), q_p from its gradient, the lumped weak form S_I dp_I/dt = sum_p V_p q_p .
  grad phi_I (impervious faces are the natural condition), and each particle takes the
  change of its nodes, p_p += sum_I phi_I dp_I (as conduction's FLIP update, [R] Algorithm 8),
  once a step at end_step, both parts together.
  On a drained node the change is the one that brings the node's projected pressure to
  the held value (p* - p_I), so the particles along a drained face drain too (a node held
  only in the gradient leaves them at a share of their start pressure forever).

The same P2G adds the pore pressure's share of the internal force, sum_p V_p p_p grad phi_I.
The passes read the general backend's stored stencil, or, on the fused backend, form each
particle's stencil themselves at x_p^t, which the hook keeps a copy of for the step
(solver/pore_kernels.py): the same weights either way. A dry scene runs exactly as before,
with nothing of this compiled or allocated.
"""
from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np

from solver import pore_kernels, shape
from solver.geometry import ring
from solver.pore_fluid_schema import diffusion_time_step, initial_pore_pressure, mobility, saturated
from solver.state import grid_geometry
from solver.thermal import held_node_values

STORAGE_CUTOFF_FRACTION = 1e-9   # nodes below this share of the smallest particle's storage hold no pressure


def _per_particle(scene, body: np.ndarray, value) -> np.ndarray:
    """value(pore_fluid) of each particle's material, 0 for a dry one."""
    per_body = []
    for b in scene.bodies:
        fluid = getattr(scene.materials[b.material], "pore_fluid", None)
        per_body.append(0.0 if fluid is None else value(fluid))
    return np.ascontiguousarray(np.array(per_body, dtype=np.float64)[body])


def setup(scene, particles) -> None:
    """The pore pressure of every particle at t = 0, and each one's fluid constants."""
    pressure = particles.require("pore_pressure")
    for index, body in enumerate(scene.bodies):
        selected = np.flatnonzero(particles.body == index)
        if selected.size and body.initial_pore_pressure is not None:
            pressure[selected] = initial_pore_pressure(scene, body, particles.x[selected])
    x = particles.extra
    x["pore_compliance"] = _per_particle(scene, particles.body, lambda f: 1.0 / f.storage_modulus)   # n / K_w
    x["pore_mobility"] = _per_particle(scene, particles.body, mobility)
    x["pore_fluid_density"] = _per_particle(scene, particles.body, lambda f: f.density)
    particles.require("darcy_flux", (particles.dimension,))


class PoreFluid:
    """The pore pressure as a hook of the step (after_forces: the flow and the force;
    after_stress: the skeleton's volume change; end_step: the particles take the step's
    change), made once a run and placed on each grid."""

    def __init__(self, scene, particles):
        self.scene = scene
        storage = particles.volume * particles.extra["pore_compliance"]
        if scene.axisymmetric:   # (the rings' volumes, which Axisymmetry sets after this)
            storage = storage * ring(particles.x)
        self.cutoff = STORAGE_CUTOFF_FRACTION * float(storage[storage > 0].min())
        self.diffusion_limit = diffusion_time_step(scene)[0]
        # (K_w / n) / rho of the stiffest saturated material: what the fluid adds to c^2
        self.wave_squared = max(m.pore_fluid.storage_modulus / m.density
                                for m in scene.materials.values() if getattr(m, "pore_fluid", None) is not None)
        self._held_whole = held_node_values(scene, grid_geometry(scene), "pore_pressure", "pressure")

    def place(self, sim) -> "PoreFluid":
        n = sim.grid.mass.shape[0]
        self.storage = np.zeros((n, 2))
        self.inflow = np.zeros(n)
        self.grid_pressure = np.zeros(n)
        self.change = np.zeros(n)
        self.squeeze = np.zeros(n)
        self.held = sim.domain.owned(self._held_whole, sim.grid)
        self.start = np.zeros((0, sim.scene.dimension))   # x_p^t, where the backend stores no stencil
        f = sim.frame
        support = shape.REGISTRY[sim.scene.method.shape_function].support   # (an empty array of its rank)
        self._at = (np.empty((0,) * support), sim.spec[0], (f.lower, f.inv_h, f.cells, f.strides, int(f.offset)))
        return self

    def _passes(self, sim) -> "_Passes":
        """The four passes on the step's stencil: the stored one, or one formed at x_p^t."""
        if sim.stencil is not None:
            s = sim.stencil
            return _Passes(pore_kernels.pressure_to_grid, pore_kernels.darcy_to_grid, pore_kernels.squeeze_to_grid,
                           pore_kernels.take_change, (s.idx, s.w, s.dw))
        return _Passes(pore_kernels.pressure_to_grid_at, pore_kernels.darcy_to_grid_at,
                       pore_kernels.squeeze_to_grid_at, pore_kernels.take_change_at, (*self._at, self.start))

    def begin_step(self, sim, t_end: float) -> None:
        self.dt = t_end - sim.time   # (USF's P2G of the forces is told no dt)
        if self.held.time_dependent:
            self.held.set_time(t_end)

    def after_forces(self, sim) -> None:
        """The pore pressure's force on the grid, and the step's flow into the particles' p.
        With slabs, each scatter's ghost nodes are summed into their owners, which compute
        the nodal pressure (shared back for Darcy's gradient) and the change (shared at end_step)."""
        p, x = sim.particles, sim.particles.extra
        if sim.stencil is None:   # (x_p^t: the passes after G2P need the step's first positions)
            if self.start.shape != p.x.shape:
                self.start = np.empty_like(p.x)
            np.copyto(self.start, p.x)
        passes = self._passes(sim)
        pressure = x["pore_pressure"]
        self.storage.fill(0.0)
        passes.pressure(*passes.stencil, p.volume, x["pore_compliance"], pressure, self.storage,
                        sim.grid.force)   # (the force's ghosts: the mechanics sums them next)
        if sim.axisymmetry is not None:   # the hoop term of p's force; Darcy's and the squeeze's weak forms
            sim.axisymmetry.add_pore_pressure_force(sim, pressure)   # take the rings' volumes and L_thth as they are
        sim.domain.sum_ghosts(self.storage)
        stored = self.storage[:, 0] > self.cutoff
        np.divide(self.storage[:, 1], self.storage[:, 0], out=self.grid_pressure, where=stored)
        self.grid_pressure[~stored] = 0.0
        projected = self.grid_pressure[self.held.node]
        self.grid_pressure[self.held.node] = self.held.value
        sim.domain.share_nodes(self.grid_pressure)
        self.inflow.fill(0.0)
        # b of Darcy's law: the step's body acceleration (gravity and the body force), as the mixture's
        passes.darcy(*passes.stencil, self.grid_pressure, x["pore_mobility"], x["pore_fluid_density"],
                     sim.phases.acceleration, p.volume, x["darcy_flux"], self.inflow)
        sim.domain.sum_ghosts(self.inflow)
        np.divide(self.dt * self.inflow, self.storage[:, 0], out=self.change, where=stored)
        self.change[~stored] = 0.0
        self.change[self.held.node] = np.where(stored[self.held.node], self.held.value - projected, 0.0)
        self.stored = stored

    def after_stress(self, sim, dt: float) -> None:
        """The skeleton's part, from the L_p the stress took: squeeze_I = sum_p phi_I V_p tr(L_p)."""
        p, x = sim.particles, sim.particles.extra
        passes = self._passes(sim)
        self.squeeze.fill(0.0)
        # the pore pressure's work on the mixture, sum dt sum_p V_p p_p tr(L_p) (J): energy the fluid
        # gave the mechanics (its stored energy, the flow), which the runner's energy check counts as supplied
        power = passes.squeeze(*passes.stencil, p.volume, p.L, x["pore_compliance"], x["pore_pressure"], self.squeeze)
        sim.work.add("pore_pressure_work", dt * power)

    def end_step(self, sim, dt: float) -> None:
        """S_I dp_I = -dt squeeze_I (0 on the drained nodes) joins the flow's change, and the
        particles take it (here, not at after_stress: USF updates the stress before its P2G)."""
        squeeze = self.squeeze
        sim.domain.sum_ghosts(squeeze)
        squeeze[self.held.node] = 0.0
        np.divide(squeeze, self.storage[:, 0], out=squeeze, where=self.stored)
        squeeze[~self.stored] = 0.0
        self.change -= dt * squeeze
        sim.domain.share_nodes(self.change)   # (the owners' values: a ghost's sums were partial)
        passes, x = self._passes(sim), sim.particles.extra
        passes.take(*passes.stencil, self.change, x["pore_compliance"], x["pore_pressure"])

    def undrained_speed(self, wave_speed: float) -> float:
        """The fastest wave with the fluid's stiffness added: sqrt(c^2 + (K_w / n) / rho)."""
        return float(np.sqrt(wave_speed * wave_speed + self.wave_squared))

    def stable_time_step(self, cfl: float) -> float:
        return cfl * self.diffusion_limit


class _Passes(NamedTuple):
    """The pore kernels of one stencil source, and the first arguments, which give each its stencil."""
    pressure: Callable
    darcy: Callable
    squeeze: Callable
    take: Callable
    stencil: tuple


def make(sim):
    """The pore fluid hook of a saturated scene (placed on the current grid), else None."""
    return None if sim.pore_fluid is None else sim.pore_fluid.place(sim)


def create(scene, particles):
    """The run's PoreFluid for a saturated scene (its particles' pore state set), else None."""
    if not saturated(scene):
        return None
    setup(scene, particles)
    return PoreFluid(scene, particles)
