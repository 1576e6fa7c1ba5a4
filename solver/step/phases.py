"""The phases the schemes (solver/step/schemes.py) are written in, and what every
backend shares: the grid update, the conditions, the stress update, the hooks and
the halo.

A backend (the general kernels in solver/step/general.py, the fused ones in
solver/step/fused.py; a GPU one would be a third) implements the particle phases:

    weights()                             phi_I(x_p), grad phi_I(x_p) where they are stored
    _p2g(acc)                             m_I, (mv)_I, f_I (with APIC's affine momentum)
    _p2g_mass_momentum()                  m_I, (mv)_I only (USF)
    _p2g_force(acc)                       f_I only (USF, after the stress update)
    grid_to_particles(dt, remap, kinematics)   v_p (and C_p); x_p by the end of kinematics;
                                          `remap`: (mv)_I again from the new v_p (MUSL);
                                          `kinematics`: L_p, F_p, V_p from the same v~_I^{t+dt} (USL)
    kinematics(dt, v_grid)                L_p, F_p, V_p (and x_p where G2P left it) from v_grid

and says which scenes it can run (`supports(scene)`).
"""
from __future__ import annotations

import numpy as np

from solver import kernels


class Phases:
    """The phases of one simulation's step; `sim` holds the state (solver/stepper.py)."""

    carries_conduction = False   # whether the backend's kernels do conduction's particle passes (fused)
    carries_contact = False      # whether they step the contact's fields and scatter its normals (fused)

    def __init__(self, sim):
        self.sim = sim
        self.dt = 0.0              # the step's dt, set by particles_to_grid
        self.acceleration = None   # the body acceleration of this step, for the loads' work

    # -- P2G ------------------------------------------------------------------

    def particles_to_grid(self, dt: float) -> None:
        """m_I, (mv)_I and f_I = sum_p m_p phi_I b_p - V_p sigma_p grad phi_I (lines 8-12); dt is
        the step's, for a backend that folds dt f_I into (mv)_I (solver/step/fused.py)."""
        sim = self.sim
        g = sim.grid
        g.reset()
        self.dt = dt
        self._p2g(self._body_acceleration())
        self._after_forces()
        sim.domain.sum_ghosts(g.mass, g.momentum, g.force)   # (processes: ghost nodes to owners)

    def mass_momentum_to_grid(self) -> None:
        """m_I and (mv)_I only: USF's first transfer."""
        g = self.sim.grid
        g.reset()
        self._p2g_mass_momentum()
        self.sim.domain.sum_ghosts(g.mass, g.momentum)

    def forces_to_grid(self) -> None:
        """f_I from the stress just updated: USF's second transfer."""
        g = self.sim.grid
        self._p2g_force(self._body_acceleration())
        self._after_forces()
        self.sim.domain.sum_ghosts(g.force)

    def _body_acceleration(self) -> np.ndarray:
        sim = self.sim
        self.acceleration = sim.loads.acceleration(sim.particles, sim.time)
        return self.acceleration

    def _after_forces(self) -> None:
        for hook in self.sim.hooks.after_forces:
            hook(self.sim)

    # -- the grid -------------------------------------------------------------

    def grid_velocities(self, dt: float) -> None:
        """v_I^t = (mv)_I / m_I and v~_I^{t+dt} = v_I^t + dt f_I / m_I, both constrained (lines 14-17)."""
        sim = self.sim
        g = sim.grid
        for hook in sim.hooks.before_update:
            hook(sim, dt)
        self._integrate(dt)
        self._constrain(g.v_old)
        sim.work.add("boundary_work", self._constrain(g.v_new, record=True))
        sim.domain.share_nodes(g.v_old, g.v_new)   # (owners' values to ghost nodes)

    def _integrate(self, dt: float) -> None:
        """v_I^t and v~_I^{t+dt}, unconstrained, from the nodal sums."""
        sim, g = self.sim, self.sim.grid
        kernels.integrate_nodes(sim.spec[0], dt, g.mass, g.momentum, g.force, sim.mass_cutoff, g.v_new)
        if g.v_old is not g.force:   # (USF's v_I^t has an array of its own: solver/state.py v_old_in_force)
            np.copyto(g.v_old, g.force)

    def current_velocities(self) -> None:
        """v_I^t = (mv)_I / m_I, constrained: USF's velocity for the stress update."""
        g = self.sim.grid
        kernels.nodal_velocity(self.sim.spec[0], g.mass, g.momentum, g.v_old)
        self._constrain(g.v_old)
        self.sim.domain.share_nodes(g.v_old)

    def remapped_velocities(self) -> None:
        """v_I^{t+dt} from the momentum the particles mapped back, constrained (lines 21, 24)."""
        sim = self.sim
        g = sim.grid
        sim.domain.sum_ghosts(g.momentum)
        kernels.nodal_velocity(sim.spec[0], g.mass, g.momentum, g.v_new)
        self._constrain(g.v_new)
        sim.domain.share_nodes(g.v_new)

    def _constrain(self, v: np.ndarray, record: bool = False) -> float:
        """Prescribed nodal velocities (the `constrain` hooks); returns their work. `record`
        marks the update to v~^{t+dt}, whose constraint impulses are the rigid bodies' reactions."""
        work = 0.0
        for hook in self.sim.hooks.constrain:
            work += hook(self.sim.grid.mass, v, record)
        return work

    # -- particles ------------------------------------------------------------

    def _after_g2p(self, dt: float) -> None:
        for hook in self.sim.hooks.after_g2p:
            hook(self.sim, dt)

    def _after_kinematics(self, dt: float, v_grid: np.ndarray) -> None:
        for hook in self.sim.hooks.after_kinematics:
            hook(self.sim, dt, v_grid)

    def stress(self, dt: float) -> None:
        """sigma_p from the materials (line 28); put off (Particles.defer) where the
        backend's P2G forms it from F_p itself (`forms_stress`); nothing where its G2P
        updated it (`updates_stress`)."""
        sim = self.sim
        if self.forms_stress():
            sim.particles.defer("stress", lambda: self._material_stress(dt))
            return
        if self.updates_stress():   # done: G2P updated it from L_p (solver/step/fused.py)
            return
        self._material_stress(dt)
        for hook in sim.hooks.after_stress:
            hook(sim, dt)

    def _material_stress(self, dt: float) -> None:
        sim = self.sim
        for material, sl in sim.materials:
            material.update_stress(sim.particles, sl, dt)

    def hooks_changed(self) -> None:
        """A hook was added (ExplicitMPM.add_hook): what the backend decided from the hooks is decided again."""

    def forms_stress(self) -> bool:
        """Whether the next P2G forms sigma_p from F_p, so that the stress update can wait
        until something reads the stress (solver/step/fused.py)."""
        return False

    def updates_stress(self) -> bool:
        """Whether the pass that formed L_p has updated sigma_p from it already (solver/step/fused.py)."""
        return False
