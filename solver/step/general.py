"""The general backend: every particle's stencil (node numbers, weights, gradients)
is stored once a step and read by one kernel per phase (solver/kernels.py), so any
shape function, both formulations, APIC, the hoop terms and rigid bodies plug in."""
from __future__ import annotations

import numpy as np

from solver import kernels, shape
from solver.state import make_stencil
from solver.step.phases import Phases


class GeneralPhases(Phases):
    name = "general"

    @staticmethod
    def supports(scene) -> bool:
        return True

    def place_particles(self) -> None:
        sim = self.sim
        p = sim.particles
        sim.stencil = make_stencil(p.count, p.dimension, sim.stencil_support)
        sim.rate = None
        sim.formulation.place_particles(p)
        if sim.formulation.reference:
            self._evaluate_weights()   # TLMPM: phi_I(X_p) and grad0 phi_I(X_p) once (Alg. 3 lines 3-4)

    def weights(self) -> None:
        if not self.sim.formulation.reference:
            self._evaluate_weights()

    def _evaluate_weights(self) -> None:
        sim = self.sim
        p = sim.particles
        x = sim.formulation.positions(p)
        outside = sim.domain.weights(sim.shape, sim.spec, x, p, sim.grid, sim.stencil)   # this process's node numbers
        while outside >= 0 and self._widen_for(x):   # a domain (CPDI) outgrew the stencil
            outside = sim.domain.weights(sim.shape, sim.spec, x, p, sim.grid, sim.stencil)
        if outside >= 0:
            told = shape.failure(sim.shape, x, p, sim.frame, outside)   # (whole-grid frame)
            if told is not None:
                sim.fail(outside, *told)
                return
            quantity, detail = sim.formulation.outside
            sim.fail(outside, quantity, detail.format(where=np.array2string(x[outside], precision=6)))
        if sim.affine is not None:   # MLS: w D_p^-1 (x_I - x_p) for grad w, before contact moves the stencil
            sim.affine.gradients(sim.spec, sim.stencil, x, sim.threads)   # into each body's field
        for hook in sim.hooks.after_weights:
            hook(sim)

    def _widen_for(self, x: np.ndarray) -> bool:
        """After the weights refused a particle: widen the stencil to the nodes per axis the
        largest domain needs (at least one more than now: the 4-node stencil keeps the corners
        within the particle's neighbouring cells, and round-off may put a corner a cell further
        than the estimate), and say whether it did. Not where the refusal had another cause (a
        folded domain, a particle outside the grid: the domains fit), nor beyond SUPPORT with
        several processes (the slabs' halo holds SUPPORT nodes, solver/parallel), the whole
        grid or what the kernels take (kernels.widest_stencil)."""
        sim = self.sim
        needed = shape.support_needed(sim.shape, x, sim.particles, sim.frame)
        widest = sim.shape.SUPPORT if sim.domain.processes > 1 else min(max(sim.frame.cells) + 1,
                                                                        kernels.widest_stencil(sim.particles.dimension))
        if needed is None or needed < sim.stencil_support or sim.stencil_support >= widest:
            return False
        self._widen_stencil(min(max(needed, sim.stencil_support + 1), widest))
        return True

    def _widen_stencil(self, support: int | None = None) -> None:
        """A stencil of `support` nodes per axis (SUPPORT if not given) for the rest of the run.
        The narrower one held the same nonzero entries in the same order, so the results do not
        depend on when this happens (bit for bit: the entries it leaves out only ever add zeros)."""
        sim = self.sim
        p = sim.particles
        sim.stencil_support = support or sim.shape.SUPPORT
        sim.spec = kernels.stencil_spec(p.dimension, sim.stencil_support**p.dimension)
        if sim.stencil_support > sim.shape.SUPPORT:   # what fields and loads evaluate on too
            sim.wide_support, sim.wide_spec = sim.stencil_support, sim.spec
        sim.stencil = make_stencil(p.count, p.dimension, sim.stencil_support)

    # -- P2G ------------------------------------------------------------------

    def _p2g(self, acc: np.ndarray) -> None:
        sim = self.sim
        p, g, s, c = sim.particles, sim.grid, sim.stencil, sim.copies
        volume, stress = sim.formulation.force_measure(sim)
        kernels.p2g(sim.spec, s.idx, s.w, s.dw, p.mass, p.v, volume, stress, acc,
                    g.mass, g.momentum, g.force, c.mass, c.momentum, c.force)
        self._affine_p2g()

    def _p2g_mass_momentum(self) -> None:
        sim = self.sim
        p, g, s, c = sim.particles, sim.grid, sim.stencil, sim.copies
        kernels.p2g_mass_momentum(sim.spec, s.idx, s.w, p.mass, p.v, g.mass, g.momentum, c.mass, c.momentum)
        self._affine_p2g()

    def _p2g_force(self, acc: np.ndarray) -> None:
        sim = self.sim
        p, g, s, c = sim.particles, sim.grid, sim.stencil, sim.copies
        volume, stress = sim.formulation.force_measure(sim)
        kernels.p2g_force(sim.spec, s.idx, s.w, s.dw, p.mass, volume, stress, acc, g.force, c.force)

    def _affine_p2g(self) -> None:
        sim = self.sim
        if sim.affine is not None:
            p = sim.particles
            sim.affine.p2g(sim.spec, sim.stencil, p, sim.formulation.positions(p), sim.grid.momentum,
                           sim.copies.momentum)

    # -- G2P ------------------------------------------------------------------

    def grid_to_particles(self, dt: float, remap: bool, kinematics: bool = False) -> None:
        sim = self.sim
        p, g, s, c = sim.particles, sim.grid, sim.stencil, sim.copies
        if remap:
            g.momentum.fill(0.0)
        if sim.affine is not None:   # C_p first: the double map needs x_p before the move
            sim.affine.g2p(sim.spec, s, p, sim.formulation.positions(p), g.v_new, remap, g.momentum, c.momentum)
        kernels.g2p(sim.spec, s.idx, s.w, dt, sim.flip_ratio, g.v_old, g.v_new,
                    p.x, p.v, p.mass, remap, g.momentum, c.momentum)
        self._after_g2p(dt)
        if kinematics:
            self.kinematics(dt, g.v_new)

    def kinematics(self, dt: float, v_grid: np.ndarray) -> None:
        sim = self.sim
        sim.check_inversion(sim.formulation.kinematics(sim, v_grid, dt))
        self._after_kinematics(dt, v_grid)
