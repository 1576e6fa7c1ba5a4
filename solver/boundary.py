"""Grid boundary conditions as (node, axis, value) constraints.

Walls fix components on a face of the grid: `stick` all of them, `slip` the
normal one; a `friction` wall is a Coulomb contact with the face at rest
(solver/contact.py: friction_wall), listed apart as (node, axis, outward sign, mu). Velocity conditions fix the given components on every node inside a
box; a value may be an expression in t, re-evaluated each step.
"""
from __future__ import annotations

import numpy as np

from solver.expressions import compile_expression

AXES = {"x": 0, "y": 1, "z": 2}


def face_nodes(grid, face: str) -> np.ndarray:
    """The nodes of a face ("x-", ..., "z+") of the grid."""
    axis = AXES[face[0]]
    layer = 0 if face[1] == "-" else int(grid.cells[axis])
    index = np.arange(grid.n_nodes)
    return np.flatnonzero((index // grid.strides[axis]) % (grid.cells[axis] + 1) == layer)


def face_material(scene, face: str):
    """The material of the bodies whose bounding box reaches the face (within a cell);
    None if no body does, or if they are of different materials (the scene refuses both)."""
    axis, upper = AXES[face[0]], face[1] == "+"
    end = (scene.grid_upper() if upper else scene.grid_lower())[axis]
    reach = scene.cell_sizes()[axis]
    names = set()
    for body in scene.bodies:
        lower, top = body.geometry.shape().bounding_box()
        if abs((top if upper else lower)[axis] - end) <= reach:
            names.add(body.material)
    return scene.materials[names.pop()] if len(names) == 1 else None


class Constraints:
    def __init__(self, scene, grid):
        nodes, axes, values, expressions, conditions = [], [], [], [], []
        friction = []   # (nodes, axis, outward sign, mu) of each frictional wall
        positions = grid.node_positions()
        dim = scene.dimension
        tol = 1e-9 * float(np.min(grid.h))
        for number, bc in enumerate(scene.boundary_conditions):
            if bc.type == "wall":
                axis = AXES[bc.face[0]]
                on_face = face_nodes(grid, bc.face)
                if bc.mode == "friction":
                    friction.append((on_face, axis, 1.0 if bc.face[1] == "+" else -1.0, bc.friction))
                    continue
                fixed_axes = range(dim) if bc.mode == "stick" else (axis,)
                for a in fixed_axes:
                    sel = on_face
                    nodes.append(sel)
                    axes.append(np.full(sel.size, a))
                    values.append(np.zeros(sel.size))
                    expressions.append(None)
                    conditions.append(np.full(sel.size, number))
            elif bc.type == "velocity":
                inside = _inside(bc.where, positions, tol)
                sel = np.flatnonzero(inside)
                for a, component in enumerate(bc.velocity):
                    if component is None:
                        continue
                    nodes.append(sel)
                    axes.append(np.full(sel.size, a))
                    conditions.append(np.full(sel.size, number))
                    if isinstance(component, str):
                        values.append(np.zeros(sel.size))
                        expressions.append(compile_expression(component, ("t",), scene.expressions))
                    else:
                        values.append(np.full(sel.size, float(component)))
                        expressions.append(None)
        if scene.axisymmetric and grid.lower[0] == 0.0:   # the axis r = 0: v_r = 0 (review App. G)
            sel = np.flatnonzero(np.arange(grid.n_nodes) % (grid.cells[0] + 1) == 0)
            nodes.append(sel)
            axes.append(np.zeros(sel.size, dtype=np.int64))
            values.append(np.zeros(sel.size))
            expressions.append(None)
            conditions.append(np.full(sel.size, -1))   # not a condition of the scene: no reaction series
        self._blocks = list(zip(values, expressions))
        self.node = np.ascontiguousarray(np.concatenate(nodes) if nodes else np.zeros(0, np.int64), dtype=np.int64)
        self.axis = np.ascontiguousarray(np.concatenate(axes) if axes else np.zeros(0, np.int64), dtype=np.int64)
        self.value = np.ascontiguousarray(np.concatenate(values) if values else np.zeros(0))
        # the index in scene.boundary_conditions of each (node, axis) entry, for its reaction
        self.condition = np.concatenate(conditions).astype(np.int64) if conditions else np.zeros(0, np.int64)
        self._offsets = np.cumsum([0] + [v.size for v in values])
        self.set_friction_walls(*_friction_columns(friction))
        self.time_dependent = any(e is not None for e in expressions)
        self.set_time(0.0)

    def set_friction_walls(self, node, axis, sign, mu) -> None:
        self.friction_node, self.friction_axis, self.friction_sign, self.friction_mu = (
            np.ascontiguousarray(a) for a in (node, axis, sign, mu))

    def set_time(self, t: float) -> None:
        if not self.time_dependent:
            return
        for i, (_, expression) in enumerate(self._blocks):
            if expression is not None:
                self.value[self._offsets[i]:self._offsets[i + 1]] = float(expression.evaluate(t=t))


def _friction_columns(walls):
    """The frictional walls' (node, axis, sign, mu) as one array each, a row per node."""
    node = np.concatenate([w[0] for w in walls]) if walls else np.zeros(0, np.int64)
    sizes = [w[0].size for w in walls]
    return (node.astype(np.int64),
            np.repeat([w[1] for w in walls], sizes).astype(np.int64),
            np.repeat([w[2] for w in walls], sizes).astype(np.float64),
            np.repeat([w[3] for w in walls], sizes).astype(np.float64))


class ConditionReactions:
    """The force of the material on each boundary condition (walls, velocity conditions), as
    rigid bodies' reactions are counted (solver/rigid.py): the constraint impulse
    m_I (v_bar - v~_I) on v~_I^{t+dt}, summed over the condition's nodes, is the force times dt
    that the condition applies to the material; its reaction is the opposite, averaged over
    the steps between two series rows. Where two conditions fix the same node and axis the
    first imposes the value and takes the impulse (the second finds it imposed already)."""

    def __init__(self, scene):
        self.impulse = np.zeros((len(scene.boundary_conditions), scene.dimension))
        self.elapsed = 0.0
        self._entries = (None, None)   # (the constraints' node array, the entries that take an impulse)

    def _first_entries(self, c, dim: int) -> np.ndarray:
        """The first entry of a scene's condition on each (node, axis): found once per placed grid."""
        if self._entries[0] is not c.node:
            mine = np.flatnonzero(c.condition >= 0)
            _, first = np.unique(c.node[mine] * dim + c.axis[mine], return_index=True)
            self._entries = (c.node, mine[first])
        return self._entries[1]

    def record(self, constraints, grid_mass, v) -> None:
        """Before the conditions are imposed on v~^{t+dt}: add their impulses."""
        c = constraints
        entries = self._first_entries(c, v.shape[1])
        node, axis = c.node[entries], c.axis[entries]
        np.add.at(self.impulse, (c.condition[entries], axis), grid_mass[node] * (c.value[entries] - v[node, axis]))

    def reactions(self, domain) -> dict[str, float]:
        """reaction_bc<i>_<axis>: mean force of the material on boundary_conditions[i] since the last call."""
        impulse = domain.sum(self.impulse)
        force = -impulse / self.elapsed if self.elapsed > 0 else np.zeros_like(impulse)
        self.impulse[:] = 0.0
        self.elapsed = 0.0
        return {f"reaction_bc{i}_{'xyz'[a]}": float(force[i, a])
                for i in range(force.shape[0]) for a in range(force.shape[1])}


def _inside(where, positions: np.ndarray, tol: float) -> np.ndarray:
    """The nodes inside a velocity condition's `where`: a box with its faces (within
    round-off: nodes on a face belong to it), any other geometry by its own test."""
    if where.type == "box":
        lower, upper = np.asarray(where.lower) - tol, np.asarray(where.upper) + tol
        return np.all((positions >= lower) & (positions <= upper), axis=1)
    from solver.geometry import from_spec   # (geometry imports nothing of this module's users)

    return np.asarray(from_spec(where).contains(positions), dtype=bool)
