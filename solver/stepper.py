"""The explicit update-Lagrangian MPM step: USL, MUSL and USF.

Each `_step_*` method is the algorithm of the papers written as a sequence of
kernels (solver/kernels.py); the line numbers refer to Algorithm 1 (MUSL) of the
Karamelo paper, which is Algorithm 2 of the MPM review.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from solver import fused, kernels, parallel, shape, threads
from solver.axisymmetric import Axisymmetry
from solver.loads import BodyLoads
from solver.parallel.single import PARTICLES_MOVED, SLABS_MOVED
from solver.rigid import RigidBodies
from solver.state import make_materials, make_particles, make_stencil, material_slices
from solver.transfer import AffineTransfer

# Nodes whose mass is below this fraction of the lightest particle's mass get no
# acceleration (review eq. 2.63, see kernels.integrate_nodes). MUSL and USF take
# L_p from bounded nodal velocities anyway; for USL this keeps L_p finite.
MASS_CUTOFF_FRACTION = 1e-9


class Instability(RuntimeError):
    """The run cannot go on: names the step, the particle (by id) and the quantity."""

    def __init__(self, step: int, time: float, particle_id: int | None, quantity: str, detail: str):
        self.step, self.time, self.particle_id, self.quantity, self.detail = step, time, particle_id, quantity, detail
        who = f"particle {particle_id}" if particle_id is not None else "the system"
        super().__init__(f"unstable at step {step} (t = {time:.6g}): {quantity} of {who}: {detail}")

    def __reduce__(self):   # sent between processes: any rank's failure stops them all
        return Instability, (self.step, self.time, self.particle_id, self.quantity, self.detail)


@dataclass
class Energies:
    kinetic: float
    strain: float
    external_work: float
    boundary_work: float

    @property
    def total(self) -> float:
        return self.kinetic + self.strain


class ExplicitMPM:
    """Particles, grid and the step of one scene."""

    def __init__(self, scene):
        self.scene = scene
        method = scene.method
        self.particles, slices = make_particles(scene)
        self.threads = threads.configure(scene, self.particles.count)   # (every process seeds every particle)
        # Every process seeded every particle: the models are made (and their particles'
        # state started) once, here, and reused whatever particles a process holds later.
        self.materials = make_materials(scene, slices, self.particles)
        self._model_of = {name: model for name, (model, _) in zip(slices, self.materials)}
        self.shape = shape.get(method.shape_function)
        self.spec = kernels.stencil_spec(scene.dimension, self.shape.SUPPORT**scene.dimension)
        shape.prepare(self.shape, scene, self.particles)
        self.loads = BodyLoads(scene)
        if self.loads.needs_reference or method.formulation == "tlmpm":   # TLMPM: slabs of X too
            self.particles.X = self.particles.x.copy()
        self.flip_ratio = float(method.flip_ratio) if method.transfer == "flip" else 0.0
        self.time = 0.0
        self.step_count = 0
        self.external_work = 0.0
        self.boundary_work = 0.0
        self._acceleration = None   # the body acceleration of the last step
        # The common scenes take the fused kernels (solver/fused.py): the same algorithm, the
        # same answer to round-off, without storing the stencil. `fused` False forces the general
        # kernels (the tests compare the two).
        self.fused = fused.supports(scene) and type(self) is ExplicitMPM
        if self.fused:
            self._step = {"usl": self._step_usl_fused, "musl": self._step_musl_fused}[method.scheme]
            self._support = fused.support_of(method.shape_function)
        else:
            self._step = {"usl": self._step_usl, "musl": self._step_musl, "usf": self._step_usf}[method.scheme]
        # One process: the whole grid. K processes: this one's slab of it (solver/parallel).
        self.domain = parallel.decompose(scene, self.shape.SUPPORT)
        self.domain.distribute(self.particles)
        self.axisymmetry = Axisymmetry(scene, self.particles) if scene.axisymmetric else None
        self.rigid = RigidBodies(scene, self.particles, self.domain)
        self.place()
        masses = self.particles.mass[self.particles.mass > 0]   # rigid particles carry none
        self.mass_cutoff = MASS_CUTOFF_FRACTION * float(self.domain.min(masses.min() if masses.size else np.inf))

    def use_general_kernels(self) -> None:
        """Step with the general (stored-stencil) kernels even where fused ones apply."""
        self.fused = False
        self._step = {"usl": self._step_usl, "musl": self._step_musl, "usf": self._step_usf}[self.scene.method.scheme]
        self._place_particles()

    # -- the step ---------------------------------------------------------------

    def advance(self, dt: float) -> None:
        """One explicit step of size dt; raises Instability when the state breaks down."""
        self.constraints.set_time(self.time + dt)
        self.rigid.begin_step(self.particles, self.spec, self.time + dt)
        self._step(dt)
        self.rigid.end_step(self.particles, dt)
        self._account_external_work(dt)
        self.time += dt
        self.step_count += 1
        self.domain.stop_if_failed()                                    # any process unstable: all stop
        moved = self.domain.migrate(self.particles, self.step_count)    # particles follow their slab
        if moved >= SLABS_MOVED:
            self._place_grid()
        if moved >= PARTICLES_MOVED:
            self._place_particles()

    def place(self) -> None:
        """Grid and per-particle work arrays for the particles this process holds now."""
        self._place_grid()
        self._place_particles()

    def _place_grid(self) -> None:
        self.grid = self.domain.grid(self.scene)
        self.frame = self.domain.frame(self.grid)
        self.constraints = self.domain.constraints(self.scene, self.grid)
        if self.axisymmetry is not None:
            self.axisymmetry.place(self.grid, self.domain.first_node(0))   # radii from whole-grid node layers
        self.copies = threads.ScatterCopies(self.grid.n_nodes, self.scene.dimension, self.threads)
        # APIC: PIC velocities plus the affine matrix C_p (solver/transfer.py)
        self.affine = AffineTransfer(self.particles, self.grid) if self.scene.method.transfer == "apic" else None

    def _place_particles(self) -> None:
        """Per-particle work arrays and material slices for the particles held here."""
        # The general kernels store each particle's stencil; the fused ones recompute it and
        # keep only v_pic between MUSL's remap and its move.
        n, dim = self.particles.count, self.scene.dimension
        self.stencil = None if self.fused else make_stencil(n, dim, self.shape.SUPPORT)
        self.rate = np.zeros((n, dim)) if self.fused else None
        slices = material_slices(self.scene, self.particles.body)
        self.materials = [(self._model_of[name], sl) for name, sl in slices.items()]

    def _step_musl(self, dt: float) -> None:
        p, g, s, c, halo = self.particles, self.grid, self.stencil, self.copies, self.domain
        self._interpolation_weights()                                   # phi_I(x_p), grad phi_I(x_p)
        g.reset()
        acc = self._acceleration = self.loads.acceleration(p, self.time)
        kernels.p2g(self.spec, s.idx, s.w, s.dw, p.mass, p.v, p.volume, p.stress, acc,
                    g.mass, g.momentum, g.force, c.mass, c.momentum, c.force)   # lines 8-12: m_I, (mv)_I, f_I
        self._add_hoop_forces()
        self._affine_p2g()
        halo.sum_ghosts(g.mass, g.momentum, g.force)                    # (processes: ghost nodes to owners)
        kernels.integrate_nodes(dt, g.mass, g.momentum, g.force,
                                self.mass_cutoff, g.v_old, g.v_new)     # lines 14, 17: v_I^t, v~_I^{t+dt}
        self._impose(g.v_old)                                           # line 15
        self.boundary_work += self._impose(g.v_new, record=True)
        halo.share_nodes(g.v_old, g.v_new)                              # (owners' values to ghost nodes)
        g.momentum.fill(0.0)
        self._affine_g2p(g.v_new, True)
        kernels.g2p(self.spec, s.idx, s.w, dt, self.flip_ratio, g.v_old, g.v_new,
                    p.x, p.v, p.mass, True, g.momentum, c.momentum)     # lines 18-20: x_p, v_p, (mv)_I again
        halo.sum_ghosts(g.momentum)
        kernels.nodal_velocity(g.mass, g.momentum, g.v_new)   # line 24: v_I^{t+dt}
        self._impose(g.v_new)                                           # line 21
        halo.share_nodes(g.v_new)
        self._update_stress(dt, g.v_new)                                # lines 25-28: L, F, V, sigma

    def _step_usl(self, dt: float) -> None:
        p, g, s, c, halo = self.particles, self.grid, self.stencil, self.copies, self.domain
        self._interpolation_weights()
        g.reset()
        acc = self._acceleration = self.loads.acceleration(p, self.time)
        kernels.p2g(self.spec, s.idx, s.w, s.dw, p.mass, p.v, p.volume, p.stress, acc, g.mass, g.momentum, g.force,
                    c.mass, c.momentum, c.force)
        self._add_hoop_forces()
        self._affine_p2g()
        halo.sum_ghosts(g.mass, g.momentum, g.force)
        kernels.integrate_nodes(dt, g.mass, g.momentum, g.force, self.mass_cutoff, g.v_old, g.v_new)
        self._impose(g.v_old)
        self.boundary_work += self._impose(g.v_new, record=True)
        halo.share_nodes(g.v_old, g.v_new)
        self._affine_g2p(g.v_new, False)
        kernels.g2p(self.spec, s.idx, s.w, dt, self.flip_ratio, g.v_old, g.v_new,
                    p.x, p.v, p.mass, False, g.momentum, c.momentum)    # particles from v_I^{t+dt}
        self._update_stress(dt, g.v_new)                                # stress last, from v_I^{t+dt}

    def _step_usf(self, dt: float) -> None:
        p, g, s, c, halo = self.particles, self.grid, self.stencil, self.copies, self.domain
        self._interpolation_weights()
        g.reset()
        kernels.p2g_mass_momentum(self.spec, s.idx, s.w, p.mass, p.v, g.mass, g.momentum, c.mass, c.momentum)
        self._affine_p2g()
        halo.sum_ghosts(g.mass, g.momentum)
        kernels.nodal_velocity(g.mass, g.momentum, g.v_old)
        self._impose(g.v_old)
        halo.share_nodes(g.v_old)
        self._update_stress(dt, g.v_old)                                # stress first, from v_I^t
        acc = self._acceleration = self.loads.acceleration(p, self.time)
        kernels.p2g_force(self.spec, s.idx, s.w, s.dw, p.mass, p.volume, p.stress, acc, g.force, c.force)
        self._add_hoop_forces()
        halo.sum_ghosts(g.force)
        kernels.integrate_nodes(dt, g.mass, g.momentum, g.force, self.mass_cutoff, g.v_old, g.v_new)
        self._impose(g.v_old)
        self.boundary_work += self._impose(g.v_new, record=True)
        halo.share_nodes(g.v_old, g.v_new)
        self._affine_g2p(g.v_new, False)
        kernels.g2p(self.spec, s.idx, s.w, dt, self.flip_ratio, g.v_old, g.v_new,
                    p.x, p.v, p.mass, False, g.momentum, c.momentum)

    def _step_usl_fused(self, dt: float) -> None:
        g, halo = self.grid, self.domain
        g.reset()
        self._fused_p2g()                                               # m_I, (mv)_I, f_I
        halo.sum_ghosts(g.mass, g.momentum, g.force)
        kernels.integrate_nodes(dt, g.mass, g.momentum, g.force, self.mass_cutoff, g.v_old, g.v_new)
        self._impose(g.v_old)
        self.boundary_work += self._impose(g.v_new, record=True)
        halo.share_nodes(g.v_old, g.v_new)
        self._fused_g2p(dt, fused.USL)                                  # v_p, x_p, then L_p, F_p, V_p
        self._update_materials(dt)

    def _step_musl_fused(self, dt: float) -> None:
        g, halo = self.grid, self.domain
        g.reset()
        self._fused_p2g()                                               # lines 8-12
        halo.sum_ghosts(g.mass, g.momentum, g.force)
        kernels.integrate_nodes(dt, g.mass, g.momentum, g.force, self.mass_cutoff, g.v_old, g.v_new)
        self._impose(g.v_old)                                           # lines 14-17
        self.boundary_work += self._impose(g.v_new, record=True)
        halo.share_nodes(g.v_old, g.v_new)
        g.momentum.fill(0.0)
        self._fused_g2p(dt, fused.REMAP)                                # lines 18-20: v_p, (mv)_I again
        halo.sum_ghosts(g.momentum)
        kernels.nodal_velocity(g.mass, g.momentum, g.v_new)             # line 24
        self._impose(g.v_new)                                           # line 21
        halo.share_nodes(g.v_new)
        self._fused_g2p(dt, fused.KINEMATICS)                           # lines 25-27: L, F, V; x_p
        self._update_materials(dt)                                      # line 28

    # -- phases -----------------------------------------------------------------

    def _fused_p2g(self) -> None:
        p, g, f, c = self.particles, self.grid, self.frame, self.copies
        acc = self._acceleration = self.loads.acceleration(p, self.time)
        bad = np.empty(self.threads, dtype=np.int64)
        fused.kernels(self.scene.dimension).p2g(
            (self._support, fused.constant(self.affine is not None), fused.constant(self.loads.any)),
            p.x, p.v, self._affine_matrix, p.mass, p.volume, p.stress, acc,
            (f.lower, f.h, f.inv_h, f.cells, f.strides, f.offset),
            g.mass, g.momentum, g.force, c.mass, c.momentum, c.force, bad)
        outside = threads.first_of(bad)
        if outside >= 0:
            self._fail(outside, "position", f"left the grid at {np.array2string(p.x[outside], precision=6)}")

    def _fused_g2p(self, dt: float, mode: int) -> None:
        p, g, f = self.particles, self.grid, self.frame
        bad = np.empty(self.threads, dtype=np.int64)
        d_inv = fused.inverse_d(self.shape, f.inv_h) if self.affine is not None else f.inv_h   # (unused without)
        fused.kernels(self.scene.dimension).g2p(
            (self._support, fused.constant(mode), fused.constant(self.affine is not None),
             fused.constant(self.flip_ratio > 0.0)),
            p.x, p.v, self._affine_matrix, p.mass, p.L, p.F, p.volume, p.volume0, self.rate,
            (f.lower, f.h, f.inv_h, f.cells, f.strides, f.offset), g.v_old, g.v_new, g.momentum,
            self.flip_ratio, dt, d_inv, self.copies.momentum, bad)
        self._check_inversion(threads.first_of(bad))

    @property
    def _affine_matrix(self) -> np.ndarray:
        """C_p for APIC; a placeholder of the right type for the kernels otherwise."""
        if self.affine is not None:
            return self.particles.extra["affine"]
        return np.zeros((1, self.scene.dimension, self.scene.dimension))

    def _interpolation_weights(self) -> None:
        p, g, s = self.particles, self.grid, self.stencil
        outside = self.domain.weights(self.shape, self.spec, p.x, p, g, s)   # node numbers of this process's grid
        if outside >= 0:
            self._fail(outside, "position", f"left the grid at {np.array2string(p.x[outside], precision=6)}")

    def _affine_p2g(self) -> None:
        if self.affine is not None:
            self.affine.p2g(self.spec, self.stencil, self.particles, self.particles.x, self.grid.momentum,
                            self.copies.momentum)

    def _affine_g2p(self, v_grid: np.ndarray, double_map: bool) -> None:
        if self.affine is not None:
            self.affine.g2p(self.spec, self.stencil, self.particles, self.particles.x, v_grid, double_map,
                            self.grid.momentum, self.copies.momentum)

    def _impose(self, v: np.ndarray, record: bool = False) -> float:
        """Prescribed nodal velocities: rigid bodies, then boundary conditions (which win where
        both apply). Returns the work of the constraints; `record` marks the update to v~^{t+dt},
        whose constraint impulses are the rigid bodies' reactions."""
        c = self.constraints
        work = self.rigid.impose(self.grid.mass, v, record)
        return work + kernels.apply_dirichlet(c.node, c.axis, c.value, self.grid.mass, v)

    def _add_hoop_forces(self) -> None:
        if self.axisymmetry is not None:
            self.axisymmetry.add_forces(self.spec, self.stencil, self.particles, self.grid.force, self.copies.force)

    def _update_stress(self, dt: float, v_grid: np.ndarray) -> None:
        p, s = self.particles, self.stencil
        self._check_inversion(kernels.update_kinematics(self.spec, s.idx, s.dw, v_grid, dt, p.L, p.F,
                                                        p.volume, p.volume0, self.threads))
        if self.axisymmetry is not None:
            self.axisymmetry.kinematics(self.spec, s, p, v_grid, dt)
        self._update_materials(dt)

    def _check_inversion(self, inverted: int) -> None:
        if inverted >= 0:
            J = float(np.linalg.det(self.particles.F[inverted]))
            self._fail(inverted, "J = det F", f"{J:.6g} <= 0 (the material point has inverted)")

    def _update_materials(self, dt: float) -> None:
        for material, sl in self.materials:
            material.update_stress(self.particles, sl, dt)

    def _account_external_work(self, dt: float) -> None:
        """Work of the body acceleration the step applied (not evaluated again), with the new velocities."""
        if not self.loads.any:
            return
        p = self.particles
        self.external_work += dt * kernels.external_power(p.mass, self._acceleration, p.v)

    def _fail(self, index: int, quantity: str, detail: str) -> None:
        """Raise Instability (processes: once every process has reached the same point)."""
        self.domain.fail(Instability(self.step_count + 1, self.time, int(self.particles.id[index]), quantity, detail))

    # -- diagnostics ------------------------------------------------------------

    @property
    def wave_speed(self) -> float:
        """The fastest material wave speed now: it follows the state (a gas's sound speed,
        an EOS stiffening under compression)."""
        return max((m.wave_speed for m, _ in self.materials), default=0.0)

    def stable_time_step(self, cfl: float) -> float:
        """dt = cfl * min_i h_i / max_p(c_dil + |v_ip|) (review eq. 2.73)."""
        speed = self.domain.max(self.wave_speed) + self.domain.max(kernels.max_speed_per_axis(self.particles.v))
        return float(cfl * np.min(self.grid.h / np.maximum(speed, 1e-300)))

    def reactions(self) -> dict[str, float]:
        """The rigid bodies' reaction forces (mean since the last call), by series name."""
        return self.rigid.reactions()

    def energies(self) -> Energies:
        p = self.particles
        strain = sum(material.strain_energy(p, sl) for material, sl in self.materials)
        local = [kernels.kinetic_energy(p.mass, p.v), float(strain), self.external_work, self.boundary_work]
        return Energies(*(float(e) for e in self.domain.sum(local)))

    def check_finite(self) -> None:
        p = self.particles
        bad = kernels.first_non_finite(p.x, p.v, p.stress)
        if bad >= 0:
            for name, array in (("position", p.x), ("velocity", p.v), ("stress", p.stress)):
                if not np.all(np.isfinite(array[bad])):
                    self._fail(bad, name, "is not finite")
                    break
        self.domain.stop_if_failed()

    def energy_scale(self) -> float:
        """sum_p m_p c^2: the energy of the bodies strained to order one, a floor for growth checks."""
        return float(self.domain.sum(np.sum(self.particles.mass))) * self.domain.max(self.wave_speed)**2
