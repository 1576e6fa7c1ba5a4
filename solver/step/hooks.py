"""Named points of the step where physics plugs in (as Karamelo's fixes are called
from its MUSL loop, src/fix.h and src/musl.cpp).

A hook is any object with one or more of these methods; at each point the step
calls the method of every hook that has one, in the order the hooks were made
(`HOOKS` below, then any added with `ExplicitMPM.add_hook`):

| point                               | where in the step                                   |
|-------------------------------------|-----------------------------------------------------|
| begin_step(sim, t_end)              | before the scheme: conditions at t + dt, rigid marks |
| after_forces(sim)                   | after P2G put f_I on the grid, before ghost sums     |
| before_update(sim, dt)              | on the summed f_I (and m_I, (mv)_I), before v_I^t and v~_I^{t+dt} are formed from them |
| constrain(grid_mass, v, record)     | on a grid velocity (v_I^t, v~_I^{t+dt}, MUSL's remapped v_I^{t+dt}) before the halo shares it; returns the constraint's work; `record` marks v~_I^{t+dt} |
| after_g2p(sim, dt)                  | after the particles took the grid velocities         |
| after_kinematics(sim, dt, v_grid)   | after L_p, F_p, V_p from the grid velocity v_grid    |
| after_stress(sim, dt)               | after the materials' stress update                   |
| end_step(sim, dt)                   | after the scheme: rigid moves, work of the loads     |

The scene's hooks, in `HOOKS` order: rigid bodies (begin_step, constrain, end_step),
boundary conditions (begin_step, constrain), hoop terms, the body loads' work
(end_step), the applied `loads` (after_forces, end_step: solver/loads.py), `damping`
(before_update, its work at after_g2p: solver/damping.py).

A hook that needs the stored stencil (the hoop terms) runs with the general kernels
only: the fused backend's `supports(scene)` refuses such scenes. Ghost sums and halo
shares are not hooks: they complete each grid phase, after every hook of the point
has added its part (solver/step/phases.py).
"""
from __future__ import annotations

from solver import kernels
from solver.damping import Damping

POINTS = ("begin_step", "after_forces", "before_update", "constrain", "after_g2p", "after_kinematics", "after_stress", "end_step")


class Hooks:
    """The hooks' bound methods, one list per point (looked up once, not every step)."""

    def __init__(self, hooks=()):
        self._hooks = []
        for point in POINTS:
            setattr(self, point, [])
        for hook in hooks:
            self.add(hook)

    def add(self, hook) -> None:
        self._hooks.append(hook)
        for point in POINTS:
            method = getattr(hook, point, None)
            if method is not None:
                getattr(self, point).append(method)


class GridConditions:
    """The scene's boundary conditions (walls, velocity conditions, the axis r = 0) as a hook;
    with `reactions` (solver/boundary.py, the `reactions` series) their impulses are counted."""

    def __init__(self, constraints, reactions=None):
        self.constraints = constraints
        self.reactions = reactions

    def begin_step(self, sim, t_end: float) -> None:
        self.constraints.set_time(t_end)

    def constrain(self, grid_mass, v, record: bool) -> float:
        c = self.constraints
        if record and self.reactions is not None:
            self.reactions.record(c, grid_mass, v)
        return kernels.apply_dirichlet(c.node, c.axis, c.value, grid_mass, v)

    def end_step(self, sim, dt: float) -> None:
        if self.reactions is not None:
            self.reactions.elapsed += dt


class ExternalWork:
    """Work of the body acceleration the step applied (not evaluated again), with the new velocities."""

    def end_step(self, sim, dt: float) -> None:
        p = sim.particles
        sim.external_work += dt * kernels.external_power(p.mass, sim.phases.acceleration, p.v)


def _rigid_bodies(sim):
    return sim.rigid if sim.rigid.any else None


def _grid_conditions(sim):
    return GridConditions(sim.constraints, sim.condition_reactions)


def _hoop_terms(sim):
    return sim.axisymmetry


def _external_work(sim):
    return ExternalWork() if sim.loads.any else None


def _applied_loads(sim):
    return sim.applied_loads


def _damping(sim):
    return Damping(sim.scene.damping) if sim.scene.damping is not None else None


# Each entry makes the hook a scene needs (or None). The order is the order their effects
# compose in: rigid bodies impose before the boundary conditions, which win where both
# apply; the loads' work is counted after the rigid bodies moved; damping acts on the
# forces of every other hook.
HOOKS = [_rigid_bodies, _grid_conditions, _hoop_terms, _external_work, _applied_loads, _damping]


def scene_hooks(sim) -> Hooks:
    """The hooks of a placed simulation (its grid, constraints and axisymmetry), then those
    added with `sim.add_hook`."""
    made = [hook for make in HOOKS if (hook := make(sim)) is not None]
    return Hooks(made + list(sim.added_hooks))
