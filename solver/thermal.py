"""Heat: explicit conduction on the step's grid ([R] 5.3, Algorithms 8 and 9), the
thermal boundary conditions, and thermal expansion of the solid models ([R] 5.26).

Conduction is a hook (solver/step/hooks.py) with a second field transferred through
the same phases, on the same stencil and time step as the mechanics (Algorithm 9):

| point         | Algorithm 8 lines | what                                                          |
|---------------|-------------------|---------------------------------------------------------------|
| begin_step    |                   | the temperature conditions' values at t and t + dt            |
| after_forces  | 3-7               | C_I, (C T)_I, Q_I^int by P2G; ghost sums                       |
| before_update | 9-10              | T_I^t, boundary heat (flux, convection), T~_I^{t+dt}, T*; halo |
| after_g2p     | 12-15             | T_p (the grid's T~ next to held nodes), remapped T_I^{t+dt}, q_p |

The flux q_p comes from the remapped grid temperature (line 13), as [R] insists.
The heat of plastic work (Johnson-Cook's Taylor-Quinney term) is added to T_p by the
material's stress update; the next P2G carries it to the grid, which is the source
term Q^ext = sum_p V_p gamma* phi_I of line 5 (m c dT_p = V gamma* dt). With the
axisymmetric ring weighting of masses and volumes, the weak form's sum V_p q_p .
grad phi_I is the axisymmetric conduction operator, the radial term included.

The particle passes (P2G; T_p and the remap's scatter; the flux gather) run here on the
general backend's stored stencil; on the fused backend (MUSL scenes, solver/fused_scope.py)
they ride inside its P2G, REMAP and KINEMATICS kernels and this hook keeps the node
passes (`carries_conduction`). Per-particle state lives in Particles.extra so that migration
and checkpoints carry it: temperature, heat_flux, heat_capacity, conductivity (and
in TLMPM nominal_heat_flux, J F^-1 q, which P2G takes with V0_p and grad0 phi_I(X_p)).

Contact "friction" (solver/contact.py): the nodal thermal arrays hold every body's field,
as the velocity arrays do, and the stencils point into them. Where the bodies touch (the
contact's nodes) their fields are in perfect thermal contact: one C-weighted temperature,
which keeps sum C T (thermal_kernels.share_temperature). The frictional work of contact and
frictional walls (sim.friction_heat, counted with friction_work on v~^{t+dt}) is known
only after the grid update, so with contact or friction the held temperatures and the halo of T_I^t,
T~_I^{t+dt} move to after_g2p, after that heat is deposited (thermal_kernels.deposit_heat);
such scenes are not fused (the fused REMAP pass would take T~ before the heat is in).
"""
from __future__ import annotations

import math

import numpy as np

from solver import kernels, thermal_kernels
from solver.expressions import compile_expression
from solver.state import grid_geometry
from solver.thermal_schema import conducts, conduction_time_step, expands

DEFAULT_TEMPERATURE = 293.15   # K: a body's temperature when neither it nor its material gives one
CAPACITY_CUTOFF_FRACTION = 1e-9   # nodes below this share of the smallest particle's m c hold no temperature


def initial_temperatures(scene, body: np.ndarray) -> np.ndarray:
    """Each particle's start temperature: its body's, else its material's room_temperature, else 293.15 K."""
    per_body = []
    for b in scene.bodies:
        material = scene.materials[b.material]
        default = getattr(material, "room_temperature", DEFAULT_TEMPERATURE)
        per_body.append(default if b.initial_temperature is None else b.initial_temperature)
    return np.array(per_body, dtype=np.float64)[body]


def _per_particle(scene, body: np.ndarray, value) -> np.ndarray:
    per_body = [value(scene.materials[b.material]) or 0.0 for b in scene.bodies]
    return np.ascontiguousarray(np.array(per_body, dtype=np.float64)[body])


def init_particles(scene, particles) -> None:
    """The thermal state, where the scene has conduction or expansion: the temperature
    (NaN left by a model that tracks none is set from the bodies), and for conduction
    the per-particle c, k and q."""
    start = initial_temperatures(scene, particles.body)
    T = particles.require("temperature", fill=math.nan)
    T[np.isnan(T)] = start[np.isnan(T)]
    if conducts(scene):
        particles.extra["heat_capacity"] = _per_particle(scene, particles.body, lambda m: m.specific_heat)
        particles.extra["conductivity"] = _per_particle(scene, particles.body, lambda m: m.thermal_conductivity)
        particles.require("heat_flux", (particles.dimension,))
        if scene.method.formulation == "tlmpm":   # the nominal flux J F^-1 q of the reference configuration
            particles.require("nominal_heat_flux", (particles.dimension,))
    if expands(scene):
        particles.extra["expansion_temperature"] = T.copy()   # T the stress last took in (rate models)
        particles.extra["start_temperature"] = T.copy()


def setup(scene, particles) -> None:
    """Thermal state for a scene that needs it; nothing at all for one without thermal keys."""
    if conducts(scene) or expands(scene):
        init_particles(scene, particles)


# --------------------------------------------------------------------------- boundary conditions

def _face_nodes(grid, face: str) -> tuple[np.ndarray, int]:
    axis = "xyz".index(face[0])
    layer = 0 if face[1] == "-" else int(grid.cells[axis])
    index = np.arange(grid.n_nodes)
    return np.flatnonzero((index // grid.strides[axis]) % (grid.cells[axis] + 1) == layer), axis


def _tributary(grid, nodes: np.ndarray, axis: int, axisymmetric: bool) -> np.ndarray:
    """The face area each node of a face stands for: the integral of its hat function
    over the face (per unit depth in 2D, 1 in 1D; the ring area 2 pi int N r dr along r
    in an axisymmetric scene)."""
    area = np.ones(nodes.size)
    for b in range(len(grid.h)):
        layer = (nodes // grid.strides[b]) % (grid.cells[b] + 1)
        h = grid.h[b]
        if b == axis:
            if axisymmetric and b == 0:   # the face r = const: its ring
                area *= 2 * math.pi * (grid.lower[0] + layer * h)
            continue
        end = (layer == 0) | (layer == grid.cells[b])
        if axisymmetric and b == 0:
            r = grid.lower[0] + layer * h
            share = np.where(layer == 0, r * h / 2 + h * h / 6,
                             np.where(layer == grid.cells[b], r * h / 2 - h * h / 6, r * h))
            area *= 2 * math.pi * share
        else:
            area *= np.where(end, h / 2, h)
    return area


class _NodeValues:
    """Whole-grid nodes with one value each (and a condition index as `axis`), in the form
    the processes' domain maps to the nodes a process owns (domain.owned)."""

    def __init__(self, node, axis, value, expressions=()):
        self.node = np.ascontiguousarray(node, dtype=np.int64)
        self.axis = np.ascontiguousarray(axis, dtype=np.int64)
        self.value = np.ascontiguousarray(value, dtype=np.float64)
        self._expressions = list(expressions)   # (slice of value, compiled expression in t)
        self.time_dependent = bool(self._expressions)

    def set_time(self, t: float) -> None:
        for sl, expression in self._expressions:
            self.value[sl] = float(expression.evaluate(t=t))


def _value(spec, definitions=None):
    """(number, None) or (0, compiled expression in t; `definitions`: the scene's named expressions)."""
    return (0.0, compile_expression(spec, ("t",), definitions)) if isinstance(spec, str) else (float(spec), None)


def held_temperatures(scene, grid) -> _NodeValues:
    """The `temperature` conditions' nodes of the whole grid and their values."""
    return held_node_values(scene, grid, "temperature", "temperature")


def held_node_values(scene, grid, condition_type: str, key: str) -> _NodeValues:
    """The nodes of the whole grid that the conditions of `condition_type` hold (a face or a box
    of nodes each) and their values (the conditions' `key`: a number or an expression in t)."""
    nodes, values, expressions, start = [], [], [], 0
    positions = None
    for bc in scene.boundary_conditions:
        if bc.type != condition_type:
            continue
        if bc.face is not None:
            sel, _ = _face_nodes(grid, bc.face)
        else:
            positions = grid.node_positions() if positions is None else positions
            tol = 1e-9 * float(np.min(grid.h))
            inside = np.all((positions >= np.asarray(bc.where.lower) - tol)
                            & (positions <= np.asarray(bc.where.upper) + tol), axis=1)
            sel = np.flatnonzero(inside)
        number, expression = _value(getattr(bc, key), scene.expressions)
        nodes.append(sel)
        values.append(np.full(sel.size, number))
        if expression is not None:
            expressions.append((slice(start, start + sel.size), expression))
        start += sel.size
    node = np.concatenate(nodes) if nodes else np.zeros(0, np.int64)
    value = np.concatenate(values) if values else np.zeros(0)
    return _NodeValues(node, np.zeros(node.size), value, expressions)


class FaceHeat:
    """heat_flux and convection conditions: each face node's area and its condition's q*, h, T_amb."""

    def __init__(self, scene, grid):
        nodes, areas, which = [], [], []
        flux, coefficient, ambient, self._flux_expressions = [], [], [], []
        for bc in scene.boundary_conditions:
            if bc.type not in ("heat_flux", "convection"):
                continue
            sel, axis = _face_nodes(grid, bc.face)
            c = len(flux)
            nodes.append(sel)
            areas.append(_tributary(grid, sel, axis, scene.axisymmetric))
            which.append(np.full(sel.size, c))
            number, expression = _value(bc.flux, scene.expressions) if bc.type == "heat_flux" else (0.0, None)
            if expression is not None:
                self._flux_expressions.append((c, expression))
            flux.append(number)
            coefficient.append(bc.coefficient if bc.type == "convection" else 0.0)
            ambient.append(bc.ambient if bc.type == "convection" else 0.0)
        node = np.concatenate(nodes) if nodes else np.zeros(0, np.int64)
        self.whole = _NodeValues(node, np.concatenate(which) if which else np.zeros(0),
                                 np.concatenate(areas) if areas else np.zeros(0))
        self.flux = np.array(flux, dtype=np.float64)
        self.coefficient = np.array(coefficient, dtype=np.float64)
        self.ambient = np.array(ambient, dtype=np.float64)

    def set_time(self, t: float) -> None:
        for c, expression in self._flux_expressions:
            self.flux[c] = float(expression.evaluate(t=t))


# --------------------------------------------------------------------------- conduction

class Conduction:
    """[R] Algorithm 8 as a hook of the step (the table in the module docstring)."""

    def __init__(self, scene, particles):
        self.scene = scene
        self.reference = scene.method.formulation == "tlmpm"   # Algorithm 8 on X_p, V0_p and Q_p
        p = particles
        mc = p.mass * p.extra["heat_capacity"]
        self.cutoff = CAPACITY_CUTOFF_FRACTION * float(mc[mc > 0].min()) if np.any(mc > 0) else 0.0
        self.boundary_heat = 0.0   # heat that entered through heat_flux and convection faces (J)
        self.unheld_friction_heat = 0.0   # frictional heat on nodes without capacity (a body that holds none)
        whole = grid_geometry(scene)
        self._held_whole = held_temperatures(scene, whole)
        self._faces = FaceHeat(scene, whole)

    def place(self, sim) -> "Conduction":
        """Nodal arrays for this process's grid (every field of it: contact has one per body);
        the conditions on the nodes it owns."""
        n = sim.grid.mass.shape[0]
        self.n_nodes = sim.grid.n_nodes
        self.threads = sim.threads
        self.heat = np.zeros((n, 3))
        self.T_old, self.T_new, self.remapped = np.zeros(n), np.zeros(n), np.zeros(n)
        self.T_change = np.zeros(n)   # T~_I - T_I, which the fused REMAP pass reads (solver/thermal_kernels.py)
        self.copies_heat = np.zeros((sim.threads - 1, n, 3))
        self.copies_remapped = np.zeros((sim.threads - 1, n))
        self.held = sim.domain.owned(self._held_whole, sim.grid)
        # 1 at the held nodes (every field), 0 elsewhere: a particle whose stencil reaches one
        # takes the grid's temperature (thermal_kernels.takes_grid_temperature)
        self.held_mark = np.zeros(n)
        thermal_kernels.hold(self.held.node, np.ones(self.held.node.size), self.n_nodes, self.held_mark)
        sim.domain.share_nodes(self.held_mark)
        self.faces = sim.domain.owned(self._faces.whole, sim.grid)
        self.T_now = self.held.value.copy()   # T* at t; held.value is T* at t + dt
        # contact: the fields exchange heat where the bodies touch; friction heats them there
        self.contact = getattr(sim, "field_contact", None)
        self.touching = np.zeros(self.n_nodes if self.contact is not None else 0, dtype=np.bool_)
        self.exchanges = self.contact is not None or sim.friction_heat.size > 0
        return self

    def begin_step(self, sim, t_end: float) -> None:
        if self.held.time_dependent:
            self.held.set_time(sim.time)
            self.T_now[:] = self.held.value
            self.held.set_time(t_end)
        self._faces.set_time(sim.time)

    def after_forces(self, sim) -> None:
        if not sim.phases.carries_conduction:   # (the fused P2G added C_I, (C T)_I, Q_I already)
            p, s = sim.particles, sim.stencil
            x = p.extra
            self.heat.fill(0.0)
            volume, flux = (p.volume0, x["nominal_heat_flux"]) if self.reference else (p.volume, x["heat_flux"])
            thermal_kernels.p2g(sim.spec, s.idx, s.w, s.dw, p.mass, x["heat_capacity"], x["temperature"], volume,
                                flux, self.heat, self.copies_heat)
        sim.domain.sum_ghosts(self.heat)

    def before_update(self, sim, dt: float) -> None:
        faces = self._faces
        rate = thermal_kernels.boundary_heat(self.faces.node, self.faces.value, faces.flux, faces.coefficient,
                                             faces.ambient, self.faces.axis, self.n_nodes, self.heat, self.cutoff)
        self.boundary_heat += dt * rate
        self._over_nodes(thermal_kernels.integrate, thermal_kernels.integrate_block,
                         dt, self.heat, self.cutoff, self.T_old, self.T_new, self.T_change)
        if not self.exchanges:   # (else once the step's frictional heat is known: after_g2p)
            self._hold_and_share(sim)

    def _over_nodes(self, threaded, block, *args) -> None:
        """A node pass of solver/thermal_kernels.py over every node: `threaded` in one block a thread,
        or with one thread `block` itself (a one-thread parallel region costs about 1 us a call)."""
        if self.threads > 1:
            threaded(*args, self.threads)
        else:
            block(0, self.heat.shape[0], *args)

    def _hold_and_share(self, sim) -> None:
        thermal_kernels.hold(self.held.node, self.T_now, self.n_nodes, self.T_old)
        thermal_kernels.hold(self.held.node, self.held.value, self.n_nodes, self.T_new)
        if sim.phases.carries_conduction:   # (never with exchanges, which change T~ after integrate)
            thermal_kernels.hold_change(self.held.node, self.T_now, self.held.value, self.n_nodes, self.T_change)
            sim.domain.share_nodes(self.T_old, self.T_new, self.T_change)
        else:
            sim.domain.share_nodes(self.T_old, self.T_new)

    def _exchange(self, sim) -> None:
        """Contact and frictional walls, before the particles take the grid's temperature change:
        the touching fields share T_I^t and T~_I^{t+dt} (perfect thermal contact, each keeping
        sum C T), and the frictional work of this step's velocity update (sim.friction_heat, on
        the nodes this process owns) goes into T~ (solver/thermal_kernels.py)."""
        if self.contact is not None:
            self.contact.touching(self.touching)
            thermal_kernels.share_temperature(self.heat, self.touching, self.n_nodes, self.cutoff, self.T_old)
            thermal_kernels.share_temperature(self.heat, self.touching, self.n_nodes, self.cutoff, self.T_new)
        if sim.friction_heat.size:
            self.unheld_friction_heat += thermal_kernels.deposit_heat(self.heat, self.touching, self.n_nodes,
                                                                      self.cutoff, sim.friction_heat, self.T_new)
        self._hold_and_share(sim)

    def after_g2p(self, sim, dt: float) -> None:
        """Lines 12-15. On the fused backend the REMAP pass did line 12 and the scatter of 13,
        and its KINEMATICS pass, next, gathers q_p (line 15): only the node passes are left here."""
        p, s = sim.particles, sim.stencil
        x = p.extra
        fused = sim.phases.carries_conduction
        if self.exchanges:   # (never fused: solver/fused_scope.py)
            self._exchange(sim)
        if not fused:
            self.remapped.fill(0.0)
            thermal_kernels.g2p_remap(sim.spec, s.idx, s.w, self.T_old, self.T_new, self.held_mark, p.mass,
                                      x["heat_capacity"], x["temperature"], self.remapped, self.copies_remapped)
        sim.domain.sum_ghosts(self.remapped)
        self._over_nodes(thermal_kernels.remapped_temperature, thermal_kernels.remapped_temperature_block,
                         self.heat, self.remapped, self.cutoff, self.T_new)
        if self.contact is not None:   # the flux at a contact node: from the touching fields' one temperature
            thermal_kernels.share_temperature(self.heat, self.touching, self.n_nodes, self.cutoff, self.T_new)
        thermal_kernels.hold(self.held.node, self.held.value, self.n_nodes, self.T_new)
        sim.domain.share_nodes(self.T_new)
        if self.reference:
            F, dim = p.F, p.dimension
            hoop = F.shape[1] > dim   # axisymmetric (F 3x3, block diagonal): the in-plane block, and J times F_thth
            thermal_kernels.reference_flux(sim.spec, s.idx, s.dw, self.T_new, x["conductivity"],
                                           F[:, :dim, :dim] if hoop else F, x["heat_flux"], x["nominal_heat_flux"],
                                           sim.threads)
            if hoop:
                x["nominal_heat_flux"] *= F[:, 2, 2, None]
        elif not fused:
            thermal_kernels.particle_flux(sim.spec, s.idx, s.dw, self.T_new, x["conductivity"], x["heat_flux"],
                                          sim.threads)

    def grid_temperature(self) -> np.ndarray:
        """T_I^{t+dt} of the last step (the remapped, smooth one [R] plots), on this process's nodes."""
        return self.T_new

    def thermal_energy(self, particles) -> float:
        x = particles.extra
        return float(thermal_kernels.thermal_energy(particles.mass, x["heat_capacity"], x["temperature"]))

    def stable_time_step(self, cfl: float) -> float:
        return cfl * conduction_time_step(self.scene)[0]


# --------------------------------------------------------------------------- thermal expansion

class ThermalExpansion:
    """After the materials' stress update, the stress of the thermal strain alpha dT I
    (thermal_kernels.expand): rate models (hypoelastic, J2) take each step's increment
    of T, total ones (neo-Hookean, Johnson-Cook's EOS pressure) the change since the start."""

    def __init__(self, scene, model_of: dict):
        # solver model -> alpha, for the expanding materials
        self.alpha_of_model = {model: float(scene.materials[name].thermal_expansion)
                               for name, model in model_of.items() if scene.materials[name].thermal_expansion}

    def after_stress(self, sim, dt: float) -> None:
        x = sim.particles.extra
        for model, sl in sim.materials:   # the slices of the particles held now
            alpha = self.alpha_of_model.get(model)
            if alpha:
                thermal_kernels.expand(sim.particles.stress[sl], x["temperature"][sl],
                                       x["expansion_temperature"][sl], alpha, model.thermal_bulk_modulus,
                                       kernels.flag(model.total_stress))

    def energy_bound(self, sim) -> float:
        """sum_p V_p 9/2 K alpha^2 (T_p - T0_p)^2: the strain energy of the thermal strain
        held fully (a clamped body), the most heating can give the mechanics at once (a
        free body heated suddenly turns it into motion). The runner counts it as supplied."""
        p, x = sim.particles, sim.particles.extra
        total = 0.0
        for model, sl in sim.materials:
            alpha = self.alpha_of_model.get(model)
            if alpha:
                rise = x["temperature"][sl] - x["start_temperature"][sl]
                total += 4.5 * model.thermal_bulk_modulus * alpha**2 * float(np.dot(p.volume[sl], rise * rise))
        return total


def make_conduction(sim):
    """The conduction hook of a scene with conduction (placed on the current grid), else None."""
    if sim.conduction is None:
        return None
    return sim.conduction.place(sim)


def make_expansion(sim):
    """The thermal expansion hook of a scene with a thermal_expansion coefficient, else None."""
    return sim.expansion
