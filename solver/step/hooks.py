"""Named points of the step where physics plugs in (as Karamelo's fixes are called
from its MUSL loop, src/fix.h and src/musl.cpp).

A hook is any object with one or more of these methods; at each point the step
calls the method of every hook that has one, in the order the hooks were made
(`HOOKS` below, then any added with `ExplicitMPM.add_hook`):

| point                               | where in the step                                   |
|-------------------------------------|-----------------------------------------------------|
| begin_step(sim, t_end)              | before the scheme: conditions at t + dt, rigid marks |
| after_weights(sim)                  | after the stencil was evaluated (general backend)    |
| after_forces(sim)                   | after P2G put f_I on the grid, before ghost sums     |
| before_update(sim, dt)              | on the summed f_I (and m_I, (mv)_I), before v_I^t and v~_I^{t+dt} are formed from them |
| constrain(grid_mass, v, record)     | on a grid velocity (v_I^t, v~_I^{t+dt}, MUSL's remapped v_I^{t+dt}) before the halo shares it; returns the constraint's work; `record` marks v~_I^{t+dt} |
| after_g2p(sim, dt)                  | after the particles took the grid velocities         |
| after_kinematics(sim, dt, v_grid)   | after L_p, F_p, V_p from the grid velocity v_grid    |
| after_stress(sim, dt)               | after the materials' stress update                   |
| end_step(sim, dt)                   | after the scheme: rigid moves, work of the loads     |

The scene's hooks, in `HOOKS` order: rigid bodies (begin_step, constrain, end_step),
contact with a field per body (after_weights, after_forces, before_update, constrain:
solver/contact.py; the rigid bodies then only move and their fields meet the others there),
boundary conditions (begin_step, constrain), hoop terms, the body loads' work
(end_step), the applied `loads` (after_forces, end_step: solver/loads.py), the `tools`
(begin_step, after_forces, end_step, their reaction series: solver/tools.py), `absorbing`
boundaries (before_update, their work at after_g2p: solver/absorbing.py), `damping`
(before_update, its work at after_g2p: solver/damping.py), heat conduction (begin_step,
after_forces, before_update, after_g2p: solver/thermal.py), thermal expansion (after_stress),
the pore fluid of a saturated soil (begin_step, after_forces, after_stress, end_step: solver/pore_fluid.py),
F-bar (after_kinematics, after_stress: solver/fbar.py), a shape function's own (the tracked
corners of cpdi_q4 and cpdi_tet4, after_g2p), a gas's density from the grid (begin_step:
solver/gas_density.py).

A hook that needs the stored stencil (the hoop terms) runs with the general kernels
only: the fused backend's `supports(scene)` refuses such scenes. Conduction's particle passes
ride inside the fused kernels of a MUSL scene (`Phases.carries_conduction`); its node passes
stay in the hook. So do the contact fields' shift and normals (`Phases.carries_contact`: the
hook then only sums the normals' ghosts at after_forces and corrects the fields). Ghost sums and halo
shares are not hooks: they complete each grid phase, after every hook of the point
has added its part (solver/step/phases.py).
"""
from __future__ import annotations

import numpy as np

from solver import contact, gas_density, kernels, pore_fluid
from solver.absorbing import AbsorbingFaces
from solver.damping import Damping
from solver.thermal import make_conduction, make_expansion
from solver.fbar import FBar

POINTS = ("begin_step", "after_weights", "after_forces", "before_update", "constrain", "after_g2p", "after_kinematics", "after_stress", "end_step")


class Hooks:
    """The hooks' bound methods, one list per point (looked up once, not every step)."""

    def __init__(self, hooks=()):
        self._hooks = []
        for point in POINTS:
            setattr(self, point, [])
        for hook in hooks:
            self.add(hook)

    def series(self) -> dict[str, float]:
        """The time series of the hooks that log one (`series()`: the contact's pair forces)."""
        out = {}
        for hook in self._hooks:
            if hasattr(hook, "series"):
                out.update(hook.series())
        return out

    def add(self, hook) -> None:
        self._hooks.append(hook)
        for point in POINTS:
            method = getattr(hook, point, None)
            if method is not None:
                getattr(self, point).append(method)


class GridConditions:
    """The scene's boundary conditions (walls, velocity conditions, the axis r = 0) as a hook,
    on every velocity field of the grid. Frictional walls act as contact does (solver/contact.py):
    on v~_I^{t+dt} and MUSL's remapped velocity, not on v_I^t; the prescribed components win.
    With `reactions` (solver/boundary.py, the `reactions` series) their impulses are counted."""

    def __init__(self, sim, reactions=None):
        self.sim, self.constraints, self.grid = sim, sim.constraints, sim.grid
        self.reactions = reactions
        self._dissipated = np.zeros(1)

    def begin_step(self, sim, t_end: float) -> None:
        self.constraints.set_time(t_end)

    def constrain(self, grid_mass, v, record: bool) -> float:
        c, g = self.constraints, self.grid
        counted = record and self.reactions is not None
        if g.fields == 1 and not c.friction_node.size:   # the common scene: as cheap as it was
            if counted:
                self.reactions.record(c, grid_mass, v)
            return kernels.apply_dirichlet(c.node, c.axis, c.value, grid_mass, v)
        work = 0.0
        walls = c.friction_node.size > 0 and v is not g.v_old
        self._dissipated[0] = 0.0
        heat = self.sim.friction_heat   # (empty without conduction)
        heat_views = g.field_views(heat) if heat.size else [heat] * g.fields
        for mass_f, v_f, heat_f in zip(g.field_views(grid_mass), g.field_views(v), heat_views):
            if walls:
                contact.friction_wall(c.friction_node, c.friction_axis, c.friction_sign, c.friction_mu, v_f, mass_f,
                                      self._dissipated, heat_f if record else heat_f[:0])
            if counted:
                self.reactions.record(c, mass_f, v_f)
            work += kernels.apply_dirichlet(c.node, c.axis, c.value, mass_f, v_f)
        if record:
            self.sim.work.add("friction_work", float(self._dissipated[0]))
        return work

    def end_step(self, sim, dt: float) -> None:
        if self.reactions is not None:
            self.reactions.elapsed += dt


class RigidMotion:
    """The rigid bodies when contact has a field per body: they move as prescribed and their
    fields meet the others in the contact (which counts their reactions); nothing is imposed."""

    def __init__(self, rigid):
        self.begin_step, self.end_step = rigid.begin_step, rigid.end_step


class ExternalWork:
    """Work of the body acceleration the step applied (not evaluated again), with the new velocities."""

    def end_step(self, sim, dt: float) -> None:
        p = sim.particles
        sim.work.add("external_work", dt * kernels.external_power(p.mass, sim.phases.acceleration, p.v))


def _rigid_bodies(sim):
    if not sim.rigid.any:
        return None
    return RigidMotion(sim.rigid) if sim.scene.contact.fields else sim.rigid


def _field_contact(sim):
    sim.field_contact = contact.FieldContact(sim) if sim.scene.contact.fields else None   # (conduction reads it)
    return sim.field_contact


def _grid_conditions(sim):
    return GridConditions(sim, sim.condition_reactions)


def _hoop_terms(sim):
    return sim.axisymmetry


def _external_work(sim):
    return ExternalWork() if sim.loads.any else None


def _applied_loads(sim):
    return sim.applied_loads


def _tools(sim):
    return sim.tools


def _absorbing_faces(sim):
    absorbing = any(condition.type == "absorbing" for condition in sim.scene.boundary_conditions)
    return AbsorbingFaces(sim.scene, sim.grid) if absorbing else None


def _fbar(sim):
    return FBar(sim) if sim.scene.method.fbar else None


def _shape_hook(sim):
    make = getattr(sim.shape, "hook", None)   # cpdi_q4: its tracked corners move (solver/shape/kernels/cpdi.py)
    return make(sim) if make is not None else None


def _damping(sim):
    return Damping(sim.scene.damping) if sim.scene.damping is not None else None


# Each entry makes the hook a scene needs (or None). The order is the order their effects
# compose in: rigid bodies impose (or the bodies' fields meet, rigid ones included) before
# the boundary conditions, which win where both apply; the loads' work is counted after the
# rigid bodies moved; damping acts on the forces of every other hook (the pore pressure's too);
# the pore pressure takes the L_p of the stress update before F-bar puts the particles' own back; F-bar averages the
# volume after the hoop terms changed it and puts the particles' own F, L and V back after
# every other stress hook.
HOOKS = [_rigid_bodies, _field_contact, _grid_conditions, _hoop_terms, _external_work, _applied_loads, _tools,
         _absorbing_faces, _damping, make_conduction, make_expansion, pore_fluid.make, _fbar, _shape_hook,
         gas_density.make]


def scene_hooks(sim) -> Hooks:
    """The hooks of a placed simulation (its grid, constraints and axisymmetry), then those
    added with `sim.add_hook`."""
    made = [hook for make in HOOKS if (hook := make(sim)) is not None]
    return Hooks(made + list(sim.added_hooks))
