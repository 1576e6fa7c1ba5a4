"""Rigid bodies: particles that move with a prescribed velocity (review 4.2.4, Algorithm 4).

A rigid body is a moving velocity boundary condition made of particles. Each
step, every grid node of a cell that holds a rigid particle gets the body's
velocity (on the axes it prescribes: a `null` component leaves that axis free,
a frictionless contact), as a Dirichlet condition on v_I^t and v~_I^{t+dt}.
Rigid particles carry no mass and no stress, so they take no part in the
momentum balance; after the step they are moved with the prescribed velocity
(eq. 4.7) whatever the grid did. The constraint impulse m_I (v_rigid - v~_I)
summed over a body's nodes, divided by dt, is the force it applies to the
material; the opposite, the force the material applies to the body (its
reaction), is logged as a time series, averaged over the steps between two
log rows.
"""
from __future__ import annotations

import numpy as np
from solver.jit import njit, prange

from solver.expressions import compile_expression
from solver.state import grid_geometry

AXES = "xyz"


@njit(cache=True)
def mark_nodes(spec, index, x, body, lower, inv_h, cells, strides, node_body, nodes, bodies, first):
    """For each rigid particle (index), the 2**dim nodes of its cell, each once: the first
    particle to reach a node gives it its body.

    Writes nodes[i], bodies[i] and first[i] (that particle) and returns how many.
    node_body must be -1 everywhere on entry; the caller resets the marked entries afterwards.
    Serial, like `impose`: which particle reaches a node first depends on the order, and
    impose's sums would change with it; rigid particles and their nodes are few.
    """
    dim, corners = len(spec[0]), 1 << len(spec[0])
    count = 0
    for i in range(index.shape[0]):
        p = index[i]
        b = body[p]
        base = 0
        for a in range(dim):
            i = int((x[p, a] - lower[a]) * inv_h[a])
            base += min(max(i, 0), cells[a] - 1) * strides[a]
        for k in range(corners):
            node = base
            for a in range(dim):
                node += ((k >> a) & 1) * strides[a]
            if node_body[node] < 0:
                node_body[node] = b
                nodes[count] = node
                bodies[count] = b
                first[count] = p
                count += 1
    return count


@njit(cache=True)
def impose(nodes, bodies, velocity, imposed, grid_mass, v, record, impulse):
    """v_I = the body's velocity on its imposed axes; returns the work sum m_I (v_b - v_I) v_b.

    With `record`, impulse[b] accumulates m_I (v_b - v_I): the force times dt that
    the body applies to the material.
    """
    work = 0.0
    for i in range(nodes.shape[0]):
        node = nodes[i]
        b = bodies[i]
        for a in range(v.shape[1]):
            if imposed[b, a]:
                j = grid_mass[node] * (velocity[b, a] - v[node, a])
                work += j * velocity[b, a]
                if record:
                    impulse[b, a] += j
                v[node, a] = velocity[b, a]
    return work


@njit(parallel=True, cache=True)
def move_particles(index, body, start, dt, velocity, x, v, F, stress):
    """Rigid particles at start + dt v_b (eq. 4.7) with velocity v_b, F = I and no stress."""
    for i in prange(index.shape[0]):   # no scratch, each particle its own rows
        p = index[i]
        b = body[p]
        for a in range(x.shape[1]):
            x[p, a] = start[i, a] + dt * velocity[b, a]
            v[p, a] = velocity[b, a]
        for a in range(F.shape[1]):
            for c in range(F.shape[2]):
                F[p, a, c] = 1.0 if a == c else 0.0
        for a in range(3):
            for c in range(3):
                stress[p, a, c] = 0.0


class RigidBodies:
    """The scene's rigid bodies: prescribed velocities, marked nodes, reactions.

    Nodes are marked in the numbers of the whole grid: a rigid particle's cell may
    have nodes in a neighbouring slab, and in TLMPM (slabs of the reference
    configuration) its current position may be anywhere. With several processes
    the marks are gathered, each process imposes the velocities on the nodes it
    owns (share_nodes gives the ghost copies their values) and counts their
    impulses, and reactions() sums them over the processes.
    """

    def __init__(self, scene, particles, domain):
        rigid_materials = {name for name, m in scene.materials.items() if m.model == "rigid"}
        dim = scene.dimension
        n_bodies = len(scene.bodies)
        self.is_rigid = np.array([b.material in rigid_materials for b in scene.bodies])
        self.any = bool(self.is_rigid.any())
        self.domain = domain
        self.names = [b.name.replace("/", "_") for b in scene.bodies]
        self.velocity = np.zeros((n_bodies, dim))       # prescribed at the end of the step
        self.imposed = np.zeros((n_bodies, dim), dtype=np.bool_)
        self._components = {}
        for b, body in enumerate(scene.bodies):
            if not self.is_rigid[b]:
                continue
            components = body.velocity if body.velocity is not None else [0.0] * dim
            self._components[b] = [compile_expression(c, ("t",), scene.expressions) if isinstance(c, str) else c for c in components]
            self.imposed[b] = [c is not None for c in components]
        self.impulse = np.zeros((n_bodies, dim))
        self._elapsed = 0.0
        if not self.any:
            return
        particles.mass[self.is_rigid[particles.body]] = 0.0   # boundary conditions, not bodies
        self._whole = grid_geometry(scene)   # one process: its grid
        self._node_body = np.full(self._whole.n_nodes, -1, dtype=np.int64)
        self._marked = np.zeros(0, dtype=np.int64)     # whole-grid numbers marked in _node_body
        self._nodes = np.zeros(0, dtype=np.int64)      # nodes to impose on, numbered on this process's grid
        self._bodies = np.zeros(0, dtype=np.int64)     # and the body of each
        self._body_seen = None   # the particles.body array the index below was built from
        self._set_velocity(0.0)
        index = self._rigid_index(particles)
        move_particles(index, particles.body, particles.x[index], 0.0, self.velocity,
                       particles.x, particles.v, particles.F, particles.stress)

    def _set_velocity(self, t: float) -> None:
        for b, components in self._components.items():
            for a, c in enumerate(components):
                if c is None:
                    self.velocity[b, a] = 0.0   # a free axis: the body does not move along it
                else:
                    self.velocity[b, a] = float(c.evaluate(t=t)) if not isinstance(c, float) else c

    def _rigid_index(self, particles) -> np.ndarray:
        """Indices of the rigid particles, rebuilt only when the particle arrays were replaced."""
        if particles.body is not self._body_seen:
            self._body_seen = particles.body
            self._index = np.flatnonzero(self.is_rigid[particles.body])
            room = self._index.size << particles.dimension
            self._buffers = tuple(np.empty(room, dtype=np.int64) for _ in range(3))
        return self._index

    # -- the step -----------------------------------------------------------------

    def begin_step(self, sim, t_end: float) -> None:
        """Mark the nodes of the rigid particles' cells and evaluate the velocities at t_end."""
        particles, spec = sim.particles, sim.spec
        self._set_velocity(t_end)
        self._node_body[self._marked] = -1
        index = self._rigid_index(particles)
        nodes, bodies, first = self._buffers
        w = self._whole
        count = mark_nodes(spec, index, particles.x, particles.body, w.lower, w.inv_h, w.cells, w.strides,
                           self._node_body, nodes, bodies, first)
        self._marked = nodes[:count]
        self._nodes, self._bodies = self._owned_marks(self._marked, bodies[:count], particles.id[first[:count]])
        self._start = particles.x[index]

    def _owned_marks(self, nodes, bodies, ids):
        """The marks on nodes owned here, in local numbers, with those other processes made on
        them; where several reach a node, the mark of the lowest particle id wins (as in one
        process, which holds its particles in id order). One process: the marks as they are."""
        d = self.domain
        local = d.owned_local(nodes)
        here = local >= 0
        arrived = d.allgather(np.stack([nodes[~here], bodies[~here], ids[~here]], axis=1))   # the others' nodes
        theirs = d.owned_local(arrived[:, 0])
        arrived, theirs = arrived[theirs >= 0], theirs[theirs >= 0]
        local, bodies = local[here], bodies[here]
        if not arrived.size:
            return local, bodies
        local, bodies = np.concatenate([local, theirs]), np.concatenate([bodies, arrived[:, 1]])
        order = np.lexsort((np.concatenate([ids[here], arrived[:, 2]]), local))   # by node, then by id
        new_node = np.ones(order.size, dtype=bool)
        new_node[1:] = local[order[1:]] != local[order[:-1]]
        first = order[new_node]
        return local[first], bodies[first]

    def constrain(self, grid_mass, v, record: bool) -> float:
        """Impose the bodies' velocities on their marked nodes; returns the work."""
        return impose(self._nodes, self._bodies, self.velocity, self.imposed, grid_mass, v, record, self.impulse)

    def end_step(self, sim, dt: float) -> None:
        p = sim.particles
        move_particles(self._index, p.body, self._start, dt, self.velocity, p.x, p.v, p.F, p.stress)
        self._elapsed += dt

    # -- output -------------------------------------------------------------------

    def reactions(self) -> dict[str, float]:
        """reaction_<body>_<axis>: mean force of the material on each rigid body since the last call
        (summed over the processes: each counts the nodes it owns)."""
        if not self.any:
            return {}
        impulse = self.domain.sum(self.impulse)
        force = -impulse / self._elapsed if self._elapsed > 0 else np.zeros_like(impulse)
        self.impulse[:] = 0.0
        self._elapsed = 0.0
        return {f"reaction_{self.names[b]}_{AXES[a]}": float(force[b, a])
                for b in np.flatnonzero(self.is_rigid) for a in range(force.shape[1])}
