"""Tools (Karamelo 4.4): rigid obstacles that move with a prescribed velocity and push
the particles that enter them by a Hertz-type penalty force.

A tool is not made of particles and has no grid field: it is a region (a polygon in
2D, a closed triangle mesh in 3D, a sphere or a box in either) that the particles may
not enter. A particle p of a deformable body found inside it at depth d (its distance
to the tool's surface) gets the force

    f_n = k G_p s_p^(dim-1) (d / s_p)^(3/2) (1 - D_p)     along the outward normal n,

where k is the tool's `stiffness`, G_p the shear modulus of the particle's material,
s_p = V0_p^(1/dim) the particle's size (its spacing, so that G (d/s)^(3/2) is a contact
pressure on the particle's face s^(dim-1)) and D_p its damage (Johnson-Cook; 0 without
damage), so that failed material no longer resists the tool, as in Karamelo. The 3/2
power is Hertz's (Karamelo eq. 4.4, F = (pi/2) G (1 + nu)/(1 - nu^2) p^(3/2), whose
length scale is left implicit; Karamelo's code uses K G p). With `friction` mu, a
Coulomb force opposes the particle's sliding relative to the tool, at most mu f_n and
at most m_p |v_t| / dt (it stops the sliding, it never reverses it).

The forces enter the step as particle external forces (after_forces: f_I += sum_p
phi_I f_p, solver/loads.py's `spread_forces`), so the contact works in TLMPM, which has
no grid contact, as in ULMPM, on one process or several (each process pushes the
particles it holds; the reactions are summed). The tool moves after the step by dt
times its velocity at the end of the step, as rigid bodies do (solver/rigid.py).

In an axisymmetric scene a tool is a body of revolution whose cross-section is its
geometry, and a particle a ring: its face is 2 pi r s (Tools below), its force the ring's.

Time series: reaction_<tool>_<axis>, the mean force of the material on the tool since
the last row (minus the sum of the forces the particles received); energy
(solver/energy.py): `tool_penalty_energy`, the penalty's potential sum_p f_n d / (5/2)
(stored), and `tool_work`, dt sum_p (f_n,p . u + f_t,p . v_p^(t+dt)): the penalty's work
at the tool's velocity u (its springs are part of the system), the friction's as the
particles receive it.

Time step: the adaptive step keeps under 2 sqrt(m / k_eff) of the particles near a tool,
k_eff = df_n / dd at the depth they may reach in the step (penalty_time_step; times the
cfl, solver/stepper.py): a stiff tool's penalty is stiffer than the material's waves.
"""
from __future__ import annotations

import math

import numpy as np
from solver.jit import njit, prange

from solver.expressions import compile_expression
from solver.geometry import from_spec
from solver.loads import spread_forces

AXES = "xyz"
BOX, SPHERE, POLYGON, MESH = 0, 1, 2, 3
KINDS = {"box": BOX, "sphere": SPHERE, "polygon": POLYGON, "mesh": MESH}


# -- depth and outward normal of the points inside a tool ----------------------------

@njit(cache=True)
def _box_depth(q, lower, upper, depth, normal):
    """Inside the box: the distance to the nearest face, and that face's outward normal."""
    for i in range(q.shape[0]):
        best, axis, sign = np.inf, -1, 0.0
        for a in range(q.shape[1]):
            below, above = q[i, a] - lower[a], upper[a] - q[i, a]
            if below < 0.0 or above < 0.0:
                axis = -1
                break
            if below < best:
                best, axis, sign = below, a, -1.0
            if above < best:
                best, axis, sign = above, a, 1.0
        if axis >= 0:
            depth[i] = best
            normal[i, axis] = sign


@njit(cache=True)
def _sphere_depth(q, center, radius, depth, normal):
    for i in range(q.shape[0]):
        r2 = 0.0
        for a in range(q.shape[1]):
            r2 += (q[i, a] - center[a]) ** 2
        r = math.sqrt(r2)
        if r < radius and r > 0.0:
            depth[i] = radius - r
            for a in range(q.shape[1]):
                normal[i, a] = (q[i, a] - center[a]) / r


@njit(cache=True)
def _polygon_depth(q, vertices, on_axis_open, depth, normal):
    """Even-odd inside test and the nearest point of the outline, over every edge; with
    `on_axis_open` (axisymmetric) an edge on the axis r = 0 is no surface: the body of
    revolution continues across it, and its mirror image's edges are never nearer."""
    n = vertices.shape[0]
    for i in range(q.shape[0]):
        px, py = q[i, 0], q[i, 1]
        inside = False
        best, cx, cy = np.inf, 0.0, 0.0
        for e in range(n):
            x0, y0 = vertices[e, 0], vertices[e, 1]
            x1, y1 = vertices[(e + 1) % n, 0], vertices[(e + 1) % n, 1]
            if (y0 <= py) != (y1 <= py):
                if px < x0 + (py - y0) * (x1 - x0) / (y1 - y0):
                    inside = not inside
            if on_axis_open and x0 == 0.0 and x1 == 0.0:
                continue
            ex, ey = x1 - x0, y1 - y0
            length2 = ex * ex + ey * ey
            s = ((px - x0) * ex + (py - y0) * ey) / length2 if length2 > 0.0 else 0.0
            s = min(max(s, 0.0), 1.0)
            nx, ny = x0 + s * ex, y0 + s * ey
            d2 = (px - nx) ** 2 + (py - ny) ** 2
            if d2 < best:
                best, cx, cy = d2, nx, ny
        if inside and best > 0.0:
            d = math.sqrt(best)
            depth[i] = d
            normal[i, 0] = (cx - px) / d
            normal[i, 1] = (cy - py) / d


@njit(cache=True, inline="always")
def _dot(u, v):
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2]   # (np.dot on vectors needs BLAS in numba)


@njit(cache=True, inline="always")
def _closest_on_triangle(p, a, b, c):
    """The point of triangle abc nearest to p (Ericson, Real-Time Collision Detection 5.1.5)."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = _dot(ab, ap), _dot(ac, ap)
    if d1 <= 0.0 and d2 <= 0.0:
        return a
    bp = p - b
    d3, d4 = _dot(ab, bp), _dot(ac, bp)
    if d3 >= 0.0 and d4 <= d3:
        return b
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        return a + (d1 / (d1 - d3)) * ab
    cp = p - c
    d5, d6 = _dot(ab, cp), _dot(ac, cp)
    if d6 >= 0.0 and d5 <= d6:
        return c
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        return a + (d2 / (d2 - d6)) * ac
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        return b + ((d4 - d3) / ((d4 - d3) + (d5 - d6))) * (c - b)
    denominator = 1.0 / (va + vb + vc)
    return a + ab * (vb * denominator) + ac * (vc * denominator)


@njit(parallel=True, cache=True)
def _mesh_depth(q, inside, triangles, depth, normal):
    """For the points inside the mesh, the nearest point of its surface (every triangle)."""
    for i in prange(q.shape[0]):   # each point its own rows
        if not inside[i]:
            continue
        p = q[i].copy()
        best = np.inf
        nearest = p
        for t in range(triangles.shape[0]):
            c = _closest_on_triangle(p, triangles[t, 0], triangles[t, 1], triangles[t, 2])
            d2 = np.sum((c - p) ** 2)
            if d2 < best:
                best, nearest = d2, c
        if best > 0.0:
            d = math.sqrt(best)
            depth[i] = d
            for a in range(3):
                normal[i, a] = (nearest[a] - p[a]) / d


@njit(cache=True)
def near_tool(x, mass, body, modulus_of_body, shift, lower, upper, rows):
    """The particles that the tool may push (with mass, of a material with a shear modulus)
    inside its bounding box, moved by `shift`: their indices in rows[:count]; returns count.
    One pass without temporaries (the numpy form of it cost as much as a third of a step)."""
    count = 0
    for p in range(x.shape[0]):
        if mass[p] <= 0.0 or modulus_of_body[body[p]] <= 0.0:
            continue
        inside = True
        for a in range(x.shape[1]):
            q = x[p, a] - shift[a]
            if q < lower[a] or q > upper[a]:
                inside = False
                break
        if inside:
            rows[count] = p
            count += 1
    return count


# -- the force ------------------------------------------------------------------------

@njit(cache=True, inline="always")
def _hertz(stiffness, modulus, s, ring, depth, damage, dim):
    """f_n = k G s^(dim-1) (d / s)^(3/2) (1 - D), times the ring length 2 pi r in an
    axisymmetric scene (1 otherwise: the same bits as without the factor)."""
    return stiffness * modulus * s ** (dim - 1) * (depth / s) ** 1.5 * (1.0 - damage) * ring


@njit(parallel=True, cache=True)
def penalty_forces(rows, depth, normal, mass, v, size, ring, modulus, damage, tool_velocity, stiffness, friction,
                   dt, force, push):
    """force[i] of particle rows[i] at `depth` inside the tool (outward `normal`): the Hertz
    penalty along the normal (its magnitude in push[i]) and Coulomb friction against the
    sliding relative to the tool."""
    dim = v.shape[1]
    for i in prange(rows.shape[0]):   # each particle its own row
        p = rows[i]
        fn = _hertz(stiffness, modulus[i], size[i], ring[i], depth[i], damage[i], dim)
        push[i] = fn
        slide = np.zeros(dim)
        along = 0.0
        for a in range(dim):
            slide[a] = v[p, a] - tool_velocity[a]
            along += slide[a] * normal[i, a]
        speed = 0.0
        for a in range(dim):
            slide[a] -= along * normal[i, a]
            speed += slide[a] * slide[a]
        speed = math.sqrt(speed)
        ft = 0.0
        if friction > 0.0 and speed > 0.0:
            ft = min(friction * fn, mass[p] * speed / dt)
        for a in range(dim):
            force[i, a] = fn * normal[i, a] - (ft * slide[a] / speed if ft > 0.0 else 0.0)


@njit(cache=True)
def penalty_energy(depth, size, ring, modulus, damage, stiffness, dim):
    """The penalty's potential, sum int_0^d f_n = sum k G s^(dim-1) s (d / s)^(5/2) / (5/2) (1 - D)
    = sum f_n d / (5/2), over the particles at `depth` inside the tool."""
    total = 0.0
    for i in range(depth.shape[0]):
        total += _hertz(stiffness, modulus[i], size[i], ring[i], depth[i], damage[i], dim) * depth[i] / 2.5
    return total


@njit(cache=True)
def penalty_time_step(near, depth, size, ring, modulus, damage, stiffness, mass, v, tool_velocity):
    """The explicit limit 2 sqrt(m / k_eff) of the particles `near` the tool (in its bounding box)
    on the penalty spring f_n = C d^(3/2), k_eff = df_n / dd = (3/2) C d^(1/2), at the depth they
    may reach in the next step: d + w dt with w their speed relative to the tool (a particle
    about to enter counts: the step it enters in is the one that kicks it). With
    d + w dt <= 2 max(d, w dt), the step is below both of
        2 sqrt(m / ((3/2) C (2 d)^(1/2)))   and   (4 m / ((3/2) C (2 w)^(1/2)))^(2/5);
    inf where no particle is near."""
    dim = v.shape[1]
    least = np.inf
    for i in range(near.shape[0]):
        p = near[i]
        # C = f_n / d^(3/2); the (1 - D) ring factors of _hertz
        c = stiffness * modulus[i] * size[i] ** (dim - 1) / size[i] ** 1.5 * (1.0 - damage[i]) * ring[i]
        if c <= 0.0:
            continue
        if depth[i] > 0.0:
            least = min(least, 2.0 * math.sqrt(mass[p] / (1.5 * c * math.sqrt(2.0 * depth[i]))))
        w = 0.0
        for a in range(dim):
            w += (v[p, a] - tool_velocity[a]) ** 2
        if w > 0.0:
            least = min(least, (4.0 * mass[p] / (1.5 * c * math.sqrt(2.0 * math.sqrt(w)))) ** 0.4)
    return least


class Tool:
    """One tool: its shape at rest, its velocity components, stiffness and friction."""

    def __init__(self, spec, dim: int, axisymmetric: bool = False, definitions=None):
        self.name = spec.name.replace("/", "_")
        self.kind = KINDS[spec.geometry.type]
        self.stiffness, self.friction = float(spec.stiffness), float(spec.friction)
        shape = from_spec(spec.geometry)
        self.lower, self.upper = (np.asarray(b, dtype=np.float64) for b in shape.bounding_box())
        self.shape = shape
        self.axisymmetric = axisymmetric
        # a box from the axis is a cylinder: its face r = 0 is the axis, no surface; the box and
        # its mirror image give the depths of the body of revolution
        self.box_lower = shape.lower.copy() if self.kind == BOX else None
        if self.kind == BOX and axisymmetric and shape.lower[0] <= 0.0:
            self.box_lower[0] = -shape.upper[0]
        components = spec.velocity if spec.velocity is not None else [0.0] * dim
        self.components = [compile_expression(c, ("t",), definitions) if isinstance(c, str) else float(c) for c in components]

    def velocity(self, t: float) -> np.ndarray:
        return np.array([c if isinstance(c, float) else float(c.evaluate(t=t)) for c in self.components])

    def depth(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Depth inside the tool (0 outside) and the outward normal of points q, in the tool's
        own frame (the positions minus its displacement). In an axisymmetric scene the shape
        is the cross-section of a body of revolution, whose nearest surface point lies in the
        point's own meridian plane: the depth in (r, z) is the depth in 3D."""
        depth, normal = np.zeros(len(q)), np.zeros_like(q)
        shape = self.shape
        if self.kind == BOX:
            _box_depth(q, self.box_lower, shape.upper, depth, normal)
        elif self.kind == SPHERE:
            _sphere_depth(q, shape.center, shape.radius, depth, normal)
        elif self.kind == POLYGON:
            _polygon_depth(q, shape.vertices, self.axisymmetric, depth, normal)
        else:
            _mesh_depth(q, shape.contains(q), shape.triangles, depth, normal)
        return depth, normal


class Tools:
    """The scene's tools as a hook (solver/step/hooks.py): begin_step (their velocities at
    the end of the step), after_forces (the penalty forces into f_I), end_step (their
    impulses and work; they move); `series()` gives their reactions. Made once per run
    (the simulation holds it, as it holds the rigid bodies): their displacement and
    impulses outlive a new placement of the grid.

    In an axisymmetric scene a particle is a ring (solver/axisymmetric.py: its mass and
    volume are the whole ring's) and a tool a body of revolution: the particle's face is
    the ring length 2 pi r times its size s = sqrt(A0) from its cross-section area
    A0 = V0 / (2 pi r0) (r0 = r / F_thth), so that forces and reactions are the whole
    ring's and the whole tool's, as the rigid bodies' reactions are."""

    def __init__(self, scene, domain):
        dim = scene.dimension
        self.domain = domain
        self.axisymmetric = bool(scene.axisymmetric)
        self.tools = [Tool(spec, dim, self.axisymmetric, scene.expressions) for spec in scene.tools]
        self.displacement = np.zeros((len(self.tools), dim))   # since t = 0; the tools move by it
        self.velocity = np.zeros((len(self.tools), dim))       # at the end of the current step
        self.impulse = np.zeros((len(self.tools), dim))        # sum dt f on the particles since the last row
        self.elapsed = 0.0
        self._dt = 0.0
        self.pushed = []   # (tool, rows, forces) of the last step: its impulses, its work
        self.normal_forces = []   # f_n n of each entry of `pushed`: the penalty's part of the forces
        self.time_step = np.inf   # 2 sqrt(m / k_eff) of the last step's pushed particles (penalty_time_step)
        modulus = [getattr(scene.materials[body.material], "shear_modulus", 0.0) for body in scene.bodies]
        self.modulus_of_body = np.array(modulus, dtype=np.float64)   # 0: a rigid body, never pushed
        self._rows = np.empty(0, dtype=np.int64)   # room for near_tool's indices
        self.cell = float(max(scene.cell_sizes()))

    def begin_step(self, sim, t_end: float) -> None:
        self._dt = t_end - sim.time
        for i, tool in enumerate(self.tools):
            self.velocity[i] = tool.velocity(t_end)

    def near(self, p, i: int):
        """(rows, depth, normal) of the particles tool i may push now or in the next step (in its
        bounding box grown by a cell, which a particle does not cross in a step under the CFL,
        and by the tool's last travel), depth 0 outside the tool; or None."""
        tool = self.tools[i]
        if self._rows.size != p.count:
            self._rows = np.empty(p.count, dtype=np.int64)
        margin = self.cell + self._dt * float(np.max(np.abs(self.velocity[i])))
        count = near_tool(p.x, p.mass, p.body, self.modulus_of_body, self.displacement[i], tool.lower - margin,
                          tool.upper + margin, self._rows)
        if count == 0:
            return None
        near = self._rows[:count].copy()
        depth, normal = tool.depth(p.x[near] - self.displacement[i])
        return near, depth, normal

    def sizes(self, p, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(s, ring) of the particles rows: s = V0^(1/dim) and ring 1, or axisymmetric
        s = sqrt(V0 F_thth / (2 pi r)) (the cross-section area at seeding) and ring 2 pi r."""
        if not self.axisymmetric:
            return p.volume0[rows] ** (1.0 / p.dimension), np.ones(rows.size)
        ring = 2.0 * math.pi * p.x[rows, 0]
        return np.sqrt(p.volume0[rows] * p.F[rows, 2, 2] / ring), ring

    def after_forces(self, sim) -> None:
        p = sim.particles
        self.pushed, self.normal_forces = [], []
        self.time_step = np.inf
        for i, tool in enumerate(self.tools):
            found = self.near(p, i)
            if found is None:
                continue
            near, depth, normal = found
            size, ring = self.sizes(p, near)
            modulus, damage = self.modulus_of_body[p.body[near]], _damage(p, near)
            self.time_step = min(self.time_step, penalty_time_step(near, depth, size, ring, modulus, damage,
                                                                   tool.stiffness, p.mass, p.v, self.velocity[i]))
            inside = depth > 0.0
            rows = near[inside]
            if rows.size == 0:
                continue
            force, push = np.zeros((rows.size, p.dimension)), np.empty(rows.size)
            normal = np.ascontiguousarray(normal[inside])
            penalty_forces(rows, depth[inside], normal, p.mass, p.v, size[inside], ring[inside], modulus[inside],
                           damage[inside], self.velocity[i], tool.stiffness, tool.friction, self._dt, force, push)
            spread_forces(sim, rows, force)
            self.pushed.append((i, rows, force))
            self.normal_forces.append(push[:, None] * normal)

    def end_step(self, sim, dt: float) -> None:
        """The impulses, and the tools' work: the penalty's at the tool's velocity (its springs
        are part of the system, their energy the stored tool_penalty_energy: the particles' own
        velocities would count the FLIP velocity, not the motion that compresses them), the
        friction's as the particles receive it (its heat is no mechanical energy of theirs)."""
        v = sim.particles.v
        for (i, rows, force), normal_force in zip(self.pushed, self.normal_forces):
            self.impulse[i] += dt * force.sum(axis=0)
            friction = force - normal_force   # (0 bit for bit without friction)
            sim.work.add("tool_work", dt * (float(np.sum(normal_force * self.velocity[i]))
                                        + float(np.sum(friction * v[rows]))))
        self.displacement += dt * self.velocity
        self.elapsed += dt

    def stored_energy(self, sim) -> float:
        """The penalty's potential now (this process's particles): every tool at its place,
        every particle at its position (`tool_penalty_energy`, solver/energy.py)."""
        p = sim.particles
        total = 0.0
        for i, tool in enumerate(self.tools):
            found = self.near(p, i)
            if found is None:
                continue
            near, depth, _ = found
            rows = near[depth > 0.0]
            size, ring = self.sizes(p, rows)
            total += penalty_energy(depth[depth > 0.0], size, ring, self.modulus_of_body[p.body[rows]],
                                    _damage(p, rows), tool.stiffness, p.dimension)
        return total

    # -- restart checkpoints (solver/checkpoint.py) ----------------------------------

    def state(self) -> dict[str, np.ndarray]:
        """What a checkpoint keeps: the displacement, the impulses (summed over the processes:
        a collective call) and time since the last series row, and the penalty's time step."""
        return {"displacement": self.displacement.copy(), "impulse": self.domain.sum(self.impulse),
                "elapsed": np.array([self.elapsed]), "time_step": np.array([self.domain.min(self.time_step)])}

    def restore(self, state: dict[str, np.ndarray], root: bool) -> None:
        """The state of a checkpoint; the impulses' total goes to one process (`root`)."""
        self.displacement[:] = state["displacement"]
        self.impulse[:] = state["impulse"] if root else 0.0
        self.elapsed = float(state["elapsed"][0])
        # the penalty's limit of the last step, which sets the next one (none in older checkpoints)
        self.time_step = float(state["time_step"][0]) if "time_step" in state else np.inf

    def series(self) -> dict[str, float]:
        """reaction_<tool>_<axis>: the mean force of the material on each tool since the last call
        (summed over the processes)."""
        total = self.domain.sum(self.impulse)
        force = -total / self.elapsed if self.elapsed > 0 else np.zeros_like(self.impulse)
        self.impulse[:] = 0.0
        self.elapsed = 0.0
        return {f"reaction_{tool.name}_{AXES[a]}": float(force[i, a])
                for i, tool in enumerate(self.tools) for a in range(force.shape[1])}


def _damage(particles, rows: np.ndarray) -> np.ndarray:
    damage = particles.extra.get("damage")
    return np.zeros(rows.size) if damage is None else np.ascontiguousarray(damage[rows], dtype=np.float64)
