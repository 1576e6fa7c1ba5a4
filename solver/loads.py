"""Loads: body accelerations (gravity plus the scene's body force expressions) and
the scene's `loads` (forces and tractions on particles, a hook of the step).

`body_force` is a force per unit mass (an acceleration), in the current (x, y, z)
and reference (X, Y, Z) coordinates and time t, as manufactured solutions need.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from solver.expressions import compile_expression
from solver.geometry import from_spec, ring
from solver.scene import SceneError
from solver.state import make_stencil
from solver.surface import body_spacing, surface_areas

CURRENT = ("x", "y", "z")
REFERENCE = ("X", "Y", "Z")


class BodyLoads:
    def __init__(self, scene):
        dim = scene.dimension
        self.dimension = dim
        self.gravity = np.zeros(dim)
        if scene.gravity is not None:
            self.gravity[:] = scene.gravity
        variables = CURRENT[:dim] + REFERENCE[:dim] + ("t",)
        self.expressions = []
        if scene.body_force is not None:
            self.expressions = [
                compile_expression(c, variables, scene.expressions) if isinstance(c, str) else float(c or 0.0)
                for c in scene.body_force
            ]
        self.needs_reference = any(
            not isinstance(e, float) and any(v in REFERENCE for v in e.variables_used) for e in self.expressions
        )
        self._shared = self.gravity.reshape(1, dim).copy()
        # fixed for the run: read every step by the fused backend
        self.varies_by_particle = bool(self.expressions)
        self.any = self.varies_by_particle or bool(np.any(self.gravity != 0.0))

    def acceleration(self, particles, t: float) -> np.ndarray:
        """(n, dim) per particle, or (1, dim) when it is the same for all."""
        if not self.expressions:
            return self._shared
        dim = self.dimension
        env = {CURRENT[a]: particles.x[:, a] for a in range(dim)}
        if particles.X is not None:
            env.update({REFERENCE[a]: particles.X[:, a] for a in range(dim)})
        env["t"] = t
        acc = np.empty((particles.count, dim))
        for a, e in enumerate(self.expressions):
            acc[:, a] = self.gravity[a] + (e if isinstance(e, float) else e.evaluate(**env))
        return acc


def keeps_reference_position(scene) -> bool:
    """Whether the particles keep X, their seeded position: TLMPM's reference, a body force in
    X, Y, Z, or the `reference_position` output field (solver/stepper.py; the memory estimate
    counts it)."""
    return (scene.method.formulation == "tlmpm" or BodyLoads(scene).needs_reference
            or "reference_position" in scene.output.fields)


class AppliedLoads:
    """The scene's `loads` as a hook: point forces and tractions on particles.

    Found once, from the particles as seeded: a force load's particles are the body's
    particles inside `where`, each with the share m_p / sum m of the total force; a
    traction's are the body's surface particles inside `where` (solver/surface.py),
    each with its area A_p. The shares live in `particles.extra["load_share"]`
    (n, loads), so they follow the particles between processes.

    after_forces: f_p = sum_i share_pi F_i(t) and f_I += sum_p phi_I(x_p) f_p, with
    the weights evaluated for the loaded particles only (the fused backend stores
    none; a few boundary particles cost little beside the step).
    end_step: their work, dt sum_p f_p . v_p^{t+dt}, into the external work.
    """

    SHARE = "load_share"

    def __init__(self, scene, particles):
        self.dimension = scene.dimension
        self.vectors = [[compile_expression(c, ("t",), scene.expressions) if isinstance(c, str) else float(c) for c in load.vector]
                        for load in scene.loads]
        share = particles.require(self.SHARE, (len(scene.loads),))
        for i, load in enumerate(scene.loads):
            share[:, i] = _shares(scene, i, particles)
        self._rows_of = (None, None)
        self.rows, self.force = np.zeros(0, dtype=np.int64), np.zeros((0, scene.dimension))

    def values(self, t: float) -> np.ndarray:
        """(loads, dim): each load's force or traction at time t."""
        return np.array([[c if isinstance(c, float) else float(c.evaluate(t=t)) for c in vector]
                         for vector in self.vectors]).reshape(len(self.vectors), self.dimension)

    def _rows(self, particles) -> np.ndarray:
        share = particles.extra[self.SHARE]
        if self._rows_of[0] is not share:   # the particles were placed again (processes)
            self._rows_of = (share, np.flatnonzero(np.any(share != 0.0, axis=1)))
        return self._rows_of[1]

    def after_forces(self, sim) -> None:
        p = sim.particles
        rows = self._rows(p)
        self.rows = rows
        self.force = p.extra[self.SHARE][rows] @ self.values(sim.time)
        spread_forces(sim, rows, self.force)

    def end_step(self, sim, dt: float) -> None:
        if self.rows.size:
            sim.work.add("external_work", dt * float(np.sum(self.force * sim.particles.v[self.rows])))


def spread_forces(sim, rows: np.ndarray, force: np.ndarray) -> None:
    """f_I += sum_p phi_I(x_p) f_p over the particles `rows` with forces `force` ((rows, dim)),
    the weights evaluated for those particles only (at X_p in TLMPM; the fused backend stores
    none). With a velocity field per body (solver/contact.py) each goes into its body's field."""
    if rows.size == 0:
        return
    p, grid = sim.particles, sim.grid
    x = np.ascontiguousarray(sim.formulation.positions(p)[rows])
    stencil = make_stencil(rows.size, p.dimension, sim.wide_support)
    subset = SimpleNamespace(extra={k: np.ascontiguousarray(a[rows]) for k, a in p.extra.items()},
                             F=np.ascontiguousarray(p.F[rows]))
    sim.domain.weights(sim.shape, sim.wide_spec, x, subset, grid, stencil)   # (outside: the step reports it)
    if grid.fields > 1:
        stencil.idx += p.body[rows][:, None] * grid.n_nodes   # field b holds body b (contact.FieldContact)
    np.add.at(grid.force, stencil.idx, stencil.w[:, :, None] * force[:, None, :])


def _shares(scene, index: int, particles) -> np.ndarray:
    """Each particle's share of load `index`: m_p / sum m (force) or A_p (traction). In an
    axisymmetric scene a particle is a ring, 2 pi r times its plane mass and volume: the
    particles are plane still here (as seeded; solver/axisymmetric.py makes them rings
    later), so the ring factor is taken here, and a traction acts on the ring's area."""
    load = scene.loads[index]
    body = next(b for b, candidate in enumerate(scene.bodies) if candidate.name == load.body)
    mine = np.flatnonzero(particles.body == body)
    where = from_spec(load.where).contains(particles.x[mine])
    rings = ring(particles.x[mine]) if scene.axisymmetric else np.ones(mine.size)
    share = np.zeros(particles.count)
    if load.type == "force":
        chosen = mine[where]
        mass = particles.mass[chosen] * rings[where]
        if mass.sum() > 0:
            share[chosen] = mass / mass.sum()
    else:
        spec = scene.bodies[body]
        _, area = surface_areas(particles.x[mine], particles.volume0[mine] * rings, scene.grid_lower(),
                                body_spacing(scene, spec))
        share[mine[where]] = area[where]
    if not np.any(share):
        what = "particles" if load.type == "force" else "surface particles"
        raise SceneError([{"path": f"loads[{index}].where",
                           "message": f"contains none of the {what} of body {load.body!r}"}])
    return share
