"""Named points of the step where physics plugs in (as Karamelo's fixes are called
from its MUSL loop, src/fix.h and src/musl.cpp).

A hook is any object with one or more of these methods; at each point the step
calls the method of every hook that has one, in the order the hooks were made
(`HOOKS` below, then any added with `ExplicitMPM.add_hook`):

| point                               | where in the step                                   |
|-------------------------------------|-----------------------------------------------------|
| begin_step(sim, t_end)              | before the scheme: conditions at t + dt, rigid marks |
| after_forces(sim)                   | after P2G put f_I on the grid, before ghost sums     |
| constrain(grid_mass, v, record)     | on a grid velocity (v_I^t, v~_I^{t+dt}, MUSL's remapped v_I^{t+dt}) before the halo shares it; returns the constraint's work; `record` marks v~_I^{t+dt} |
| after_g2p(sim, dt)                  | after the particles took the grid velocities         |
| after_kinematics(sim, dt, v_grid)   | after L_p, F_p, V_p from the grid velocity v_grid    |
| after_stress(sim, dt)               | after the materials' stress update                   |
| end_step(sim, dt)                   | after the scheme: rigid moves, work of the loads     |

A hook that needs the stored stencil (the hoop terms) runs with the general kernels
only: the fused backend's `supports(scene)` refuses such scenes. Ghost sums and halo
shares are not hooks: they complete each grid phase, after every hook of the point
has added its part (solver/step/phases.py).
"""
from __future__ import annotations

from solver import kernels

POINTS = ("begin_step", "after_forces", "constrain", "after_g2p", "after_kinematics", "after_stress", "end_step")


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
    """The scene's boundary conditions (walls, velocity conditions, the axis r = 0) as a hook."""

    def __init__(self, constraints):
        self.constraints = constraints

    def begin_step(self, sim, t_end: float) -> None:
        self.constraints.set_time(t_end)

    def constrain(self, grid_mass, v, record: bool) -> float:
        c = self.constraints
        return kernels.apply_dirichlet(c.node, c.axis, c.value, grid_mass, v)


class ExternalWork:
    """Work of the body acceleration the step applied (not evaluated again), with the new velocities."""

    def end_step(self, sim, dt: float) -> None:
        p = sim.particles
        sim.external_work += dt * kernels.external_power(p.mass, sim.phases.acceleration, p.v)


def _rigid_bodies(sim):
    return sim.rigid if sim.rigid.any else None


def _grid_conditions(sim):
    return GridConditions(sim.constraints)


def _hoop_terms(sim):
    return sim.axisymmetry


def _external_work(sim):
    return ExternalWork() if sim.loads.any else None


# Each entry makes the hook a scene needs (or None). The order is the order their effects
# compose in: rigid bodies impose before the boundary conditions, which win where both
# apply; the loads' work is counted after the rigid bodies moved.
HOOKS = [_rigid_bodies, _grid_conditions, _hoop_terms, _external_work]


def scene_hooks(sim) -> Hooks:
    """The hooks of a placed simulation (its grid, constraints and axisymmetry), then those
    added with `sim.add_hook`."""
    made = [hook for make in HOOKS if (hook := make(sim)) is not None]
    return Hooks(made + list(sim.added_hooks))
