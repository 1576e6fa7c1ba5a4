"""The simulation of one scene: particles, grid, and the explicit step.

`ExplicitMPM` holds the state and places it on the grid (and, with several
processes, on this process's slab); the step itself is written once per scheme in
solver/step/schemes.py, over phases that a backend implements (solver/step/), for
the formulation the scene names (ULMPM or TLMPM), with the physics that is not the
bare algorithm (rigid bodies, boundary conditions, hoop terms, the loads, damping)
plugged in at named hook points.
"""
from __future__ import annotations

import numpy as np

from solver import energy, kernels, parallel, pore_fluid, shape, step, thermal, threads
from solver.axisymmetric import Axisymmetry
from solver.boundary import ConditionReactions
from solver.contact import domain_support
from solver.energy import Energies
from solver.errors import SolverError
from solver.loads import AppliedLoads, BodyLoads, keeps_reference_position
from solver.parallel.single import PARTICLES_MOVED, SLABS_MOVED
from solver.rigid import RigidBodies
from solver.state import make_materials, make_particles, material_slices
from solver.tools import Tools
from solver.thermal_schema import conducts, expands
from solver.transfer import affine_transfer

# Nodes whose mass is below this fraction of the lightest particle's mass get no
# acceleration (review eq. 2.63, see kernels.integrate_nodes). MUSL and USF take
# L_p from bounded nodal velocities anyway; for USL this keeps L_p finite.
MASS_CUTOFF_FRACTION = 1e-9


class Instability(SolverError, RuntimeError):
    """The run cannot go on: names the step, the particle (by id) and the quantity."""

    def __init__(self, step: int, time: float, particle_id: int | None, quantity: str, detail: str):
        self.step, self.time, self.particle_id, self.quantity, self.detail = step, time, particle_id, quantity, detail
        who = f"particle {particle_id}" if particle_id is not None else "the system"
        super().__init__(f"unstable at step {step} (t = {time:.6g}): {quantity} of {who}: {detail}")

    def __reduce__(self):   # sent between processes: any rank's failure stops them all
        return Instability, (self.step, self.time, self.particle_id, self.quantity, self.detail)


class ExplicitMPM:
    """Particles, grid and the step of one scene (ULMPM or TLMPM, as the scene says)."""

    def __init__(self, scene, general: bool = False):
        """`general` steps with the general kernels even where the fused ones apply (the
        tests compare the two)."""
        self.scene = scene
        method = scene.method
        self.particles, slices = make_particles(scene)
        self.threads = threads.configure(scene, self.particles.count)   # (every process seeds every particle)
        # Every process seeded every particle: the models are made (and their particles'
        # state started) once, here, and reused whatever particles a process holds later.
        self.materials = make_materials(scene, slices, self.particles)
        self._model_of = {name: model for name, (model, _) in zip(slices, self.materials)}
        thermal.setup(scene, self.particles)   # nothing without thermal keys
        self.conduction = thermal.Conduction(scene, self.particles) if conducts(scene) else None
        self.expansion = thermal.ThermalExpansion(scene, self._model_of) if expands(scene) else None
        self.pore_fluid = pore_fluid.create(scene, self.particles)   # saturated soils only
        self.shape = shape.get(method.shape_function)
        # CPDI starts on a compact stencil and widens it when a domain needs it (solver/step/general.py)
        self.stencil_support = self.shape.COMPACT_SUPPORT or self.shape.SUPPORT
        self.spec = kernels.stencil_spec(scene.dimension, self.stencil_support**scene.dimension)
        # the stencil of weights evaluated outside the step (fields, loads): SUPPORT, or the
        # step's once a CPDI domain needed more
        self.wide_support = self.shape.SUPPORT
        self.wide_spec = kernels.stencil_spec(scene.dimension, self.wide_support**scene.dimension)
        shape.prepare(self.shape, scene, self.particles)
        self.loads = BodyLoads(scene)
        self.applied_loads = AppliedLoads(scene, self.particles) if scene.loads else None   # as seeded
        self.formulation = step.FORMULATIONS[method.formulation]()
        if keeps_reference_position(scene):   # TLMPM: slabs of X too
            self.particles.X = self.particles.x.copy()
        self.flip_ratio = float(method.flip_ratio) if method.transfer == "flip" else 0.0
        self.time = 0.0
        self.step_count = 0
        self.work = energy.WorkLedger(scene)   # the work terms, this process's share (solver/energy.py)
        self.scheme = step.SCHEMES[method.scheme]
        self.phases = step.backend_for(scene, general)(self)
        self.added_hooks = []   # hooks given by add_hook, kept when the grid is placed again
        # One process: the whole grid. K processes: this one's slab of it (solver/parallel).
        self.domain = parallel.decompose(scene, domain_support(scene, self.shape.SUPPORT))
        self.domain.distribute(self.particles)
        self.axisymmetry = Axisymmetry(scene, self.particles) if scene.axisymmetric else None
        self.rigid = RigidBodies(scene, self.particles, self.domain)
        self.tools = Tools(scene, self.domain) if scene.tools else None   # solver/tools.py
        # the boundary conditions' reactions, kept across placements of the grid (the `reactions` series)
        self.condition_reactions = ConditionReactions(scene) if "reactions" in scene.output.series else None
        self.place()
        masses = self.particles.mass[self.particles.mass > 0]   # rigid particles carry none
        self.mass_cutoff = MASS_CUTOFF_FRACTION * float(self.domain.min(masses.min() if masses.size else np.inf))

    def add_hook(self, hook) -> None:
        """Plug an object with any of the hook methods (solver/step/hooks.py) into the step,
        after the scene's own hooks."""
        self.added_hooks.append(hook)
        self.hooks.add(hook)
        self.phases.hooks_changed()

    @property
    def fused(self) -> bool:
        return self.phases.name == "fused"

    def use_general_kernels(self) -> None:
        """Step with the general (stored-stencil) kernels even where fused ones apply."""
        self.phases = step.GeneralPhases(self)
        self._place_particles()

    # -- the step ---------------------------------------------------------------

    def advance(self, dt: float) -> None:
        """One explicit step of size dt; raises Instability when the state breaks down."""
        for hook in self.hooks.begin_step:
            hook(self, self.time + dt)
        self.scheme(self.phases, dt)
        for hook in self.hooks.end_step:
            hook(self, dt)
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
        self.copies = threads.ScatterCopies(self.grid.mass.shape[0], self.scene.dimension, self.threads)   # every field
        # the frictional work's heat at each node and field this step (contact, frictional walls),
        # which conduction puts into the temperature (solver/thermal.py); empty without conduction
        heated = self.conduction is not None and energy.frictional(self.scene)
        self.friction_heat = np.zeros(self.grid.mass.shape[0] if heated else 0)
        # APIC, MLS: PIC velocities plus the affine matrix C_p (solver/transfer.py)
        self.affine = affine_transfer(self.scene, self.particles, self.grid)
        self.hooks = step.scene_hooks(self)

    def material_model(self, name: str):
        """The model of scene material `name` (made once; None for a material no body is made of)."""
        return self._model_of.get(name)

    def _place_particles(self) -> None:
        """Per-particle work arrays (the backend's) and material slices for the particles held here."""
        self.phases.place_particles()
        slices = material_slices(self.scene, self.particles.body)
        self.materials = [(self._model_of[name], sl) for name, sl in slices.items()]

    def check_inversion(self, inverted: int) -> None:
        if inverted >= 0:
            J = float(np.linalg.det(self.particles.F[inverted]))
            self.fail(inverted, "J = det F", f"{J:.6g} <= 0 (the material point has inverted)")

    def fail(self, index: int, quantity: str, detail: str) -> None:
        """Raise Instability (processes: once every process has reached the same point)."""
        self.domain.fail(Instability(self.step_count + 1, self.time, int(self.particles.id[index]), quantity, detail))

    # -- diagnostics ------------------------------------------------------------

    @property
    def wave_speed(self) -> float:
        """The fastest material wave speed now: it follows the state (a gas's sound speed,
        an EOS stiffening under compression)."""
        if any(getattr(m, "stress_sets_wave_speed", False) for m, _ in self.materials):
            self.particles.stress   # (so that a stress update put off runs: Particles.defer)
        return max((m.wave_speed for m, _ in self.materials), default=0.0)

    def stable_time_step(self, cfl: float) -> float:
        """dt = cfl * min_i h_i / max_p(c_dil + |v_ip|) (review eq. 2.73), times the formulation's factor;
        at most cfl times conduction's limit and the tools' penalty limit (solver/tools.py), where they are."""
        wave = self.domain.max(self.wave_speed)
        if self.pore_fluid is not None:   # the pore fluid stiffens the mixture against volume change
            wave = self.pore_fluid.undrained_speed(wave)
        speed = wave + self.domain.max(kernels.max_speed_per_axis(self.particles.v))
        dt = float(cfl * np.min(self.grid.h / np.maximum(speed, 1e-300))) * self.formulation.time_step_factor(self)
        if self.conduction is not None:   # and the explicit conduction's limit rho c h^2 / (2 d k)
            dt = min(dt, self.conduction.stable_time_step(cfl))
        if self.pore_fluid is not None:   # and the pore pressure's diffusion limit
            dt = min(dt, self.pore_fluid.stable_time_step(cfl))
        if self.tools is not None:   # and the penalty springs of the particles near a tool (its last step)
            dt = min(dt, cfl * self.domain.min(self.tools.time_step))
        return dt

    def reactions(self) -> dict[str, float]:
        """The rigid bodies' reaction forces and the hooks' force series (contact pairs), means
        since the last call, by series name."""
        return {**self.rigid.reactions(), **self.hooks.series()}

    def energies(self) -> Energies:
        """The energy balance's terms now (solver/energy.py), summed over the processes."""
        return energy.measure(self)

    def expansion_energy_bound(self) -> float:
        """The most mechanical energy thermal expansion can have given so far (solver/thermal.py),
        summed over the processes: the growth check counts it as supplied."""
        if self.expansion is None:
            return 0.0
        return float(self.domain.sum([self.expansion.energy_bound(self)])[0])

    def thermal_series(self) -> dict[str, float]:
        """thermal_energy (sum m c T) and the heat that came in through heat_flux and
        convection faces, for a scene with conduction; nothing otherwise."""
        if self.conduction is None:
            return {}
        local = [self.conduction.thermal_energy(self.particles), self.conduction.boundary_heat]
        energy, heat_in = (float(e) for e in self.domain.sum(local))
        return {"thermal_energy": energy, "boundary_heat": heat_in}

    def check_finite(self) -> None:
        p = self.particles
        bad = kernels.first_non_finite(p.x, p.v, p.stress)
        if bad >= 0:
            for name, array in (("position", p.x), ("velocity", p.v), ("stress", p.stress)):
                if not np.all(np.isfinite(array[bad])):
                    self.fail(bad, name, "is not finite")
                    break
        self.domain.stop_if_failed()

    def energy_scale(self) -> float:
        """sum_p m_p c^2: the energy of the bodies strained to order one, a floor for growth checks."""
        return float(self.domain.sum(np.sum(self.particles.mass))) * self.domain.max(self.wave_speed)**2
