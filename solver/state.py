"""Struct-of-arrays state of particles and grid, allocated for what a scene needs."""
from __future__ import annotations

from dataclasses import dataclass, field, fields

import numpy as np

from solver import initial_stress, materials
from solver.expressions import compile_expression
from solver.seeding import seed


class _Deferred:
    """A per-particle array whose update a step may put off (`Particles.defer`): the fused
    step forms the stress of a material that is a function of F_p alone inside P2G, and
    MLS's L_p after a USL gather is C_p (solver/step/fused.py), so the step need not store
    them. Any read of the attribute runs the pending update first, so what outputs, checks,
    checkpoints, materials and hooks read is always the current state; the array stays
    `derived` (a function of the state) until it is assigned: the new array is the state."""

    def __set_name__(self, owner, name: str) -> None:
        self.name = name

    def __get__(self, particles, owner=None):
        if particles is None:   # (the dataclass asks the class for a default: there is none)
            raise AttributeError(self.name)
        update = particles._pending.pop(self.name, None) if particles._pending else None
        if update is not None:
            update()
        return particles.__dict__[self.name]

    def __set__(self, particles, value) -> None:
        particles.__dict__.setdefault("_pending", {}).pop(self.name, None)
        particles.__dict__.setdefault("_derived", set()).discard(self.name)
        particles.__dict__[self.name] = value


@dataclass
class Particles:
    """One contiguous array per particle quantity, particles sorted by material."""

    x: np.ndarray          # (n, dim) current position
    v: np.ndarray          # (n, dim) velocity
    F: np.ndarray          # (n, dim, dim) deformation gradient
    L: np.ndarray = _Deferred()        # (n, dim, dim) velocity gradient of the last step
    stress: np.ndarray = _Deferred()   # (n, 3, 3) Cauchy stress
    mass: np.ndarray       # (n,)
    volume: np.ndarray     # (n,) current volume
    volume0: np.ndarray    # (n,) reference volume
    id: np.ndarray         # (n,) int64, stable over the run
    body: np.ndarray       # (n,) int32, index into scene.bodies
    X: np.ndarray | None = None   # (n, dim) reference position, only when a body force needs it
    # Per-particle state only some models need (plastic strain, temperature,
    # internal energy, ...), by name, each (n, ...); allocated with `require`.
    extra: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def count(self) -> int:
        return self.x.shape[0]

    @property
    def dimension(self) -> int:
        return self.x.shape[1]

    def defer(self, name: str, update) -> None:
        """Put the update of the array `name` off: `update()` brings it up to date, and runs at
        its first read (`_Deferred`) unless the step forms it itself first. (`_pending`, name ->
        update, and `_derived` are made by the first assignment of a `_Deferred` array.)"""
        self._pending[name] = update
        self._derived.add(name)

    def pending(self, name: str) -> bool:
        """Whether the stored array `name` is out of date, its update put off (`defer`)."""
        return name in self._pending

    def derived(self, name: str) -> bool:
        """Whether the array `name` is what its deferred update forms from the state (pending,
        or brought up to date by a read since), not state of its own (an initial stress, an
        array assigned). A step that forms it may then form it again rather than read it,
        whatever was read in between: a frame or a checkpoint then leaves the bits alone even
        where the step's own formula rounds differently from the update (FMA contraction).
        Writing into a derived array in place does not make it state: assign it."""
        return name in self._derived

    @property
    def derived_names(self) -> tuple[str, ...]:
        return tuple(sorted(self._derived))

    def mark_derived(self, names) -> None:
        """Mark arrays assigned from a state where they were `derived` (a checkpoint's) as derived."""
        self._derived.update(names)

    def stored(self, name: str) -> np.ndarray:
        """The array `name` as stored, without running a pending update: for a kernel that
        forms or overwrites it itself while it is pending."""
        return self.__dict__[name]

    def require(self, name: str, tail: tuple[int, ...] = (), fill: float = 0.0) -> np.ndarray:
        """The extra per-particle array `name`, allocated (filled with `fill`) on first use."""
        if name not in self.extra:
            self.extra[name] = np.full((self.count, *tail), fill)
        return self.extra[name]

    def arrays(self) -> dict[str, np.ndarray]:
        """Every per-particle array by name, the extra ones as "extra/<name>".

        Whatever moves or stores whole particles (checkpoints, migration between
        processes) goes through this, so a new quantity is never left behind.
        """
        out = {f.name: getattr(self, f.name) for f in fields(self)
               if f.name != "extra" and getattr(self, f.name) is not None}
        out.update({f"extra/{name}": a for name, a in self.extra.items()})
        return out

    def take(self, order: np.ndarray) -> None:
        """Keep the particles `order` (indices), in that order, in every array (np.take: numpy's
        fancy indexing copies (n, 3, 3) rows 4-5x slower)."""
        self.replace({name: np.take(a, order, axis=0) for name, a in self.arrays().items()}, rearranged=True)

    def replace(self, arrays: dict[str, np.ndarray], rearranged: bool = False) -> None:
        """Set the per-particle arrays named as arrays() names them (all the same length);
        `rearranged`: they hold the same state's rows, reordered or moved between processes,
        so an array that was `derived` still is."""
        derived = self.derived_names if rearranged else ()
        for name, a in arrays.items():
            a = np.ascontiguousarray(a)
            if name.startswith("extra/"):
                self.extra[name[len("extra/"):]] = a
            else:
                setattr(self, name, a)
        self.mark_derived(derived)


@dataclass
class Grid:
    """A regular background grid; nodes are numbered with x fastest.

    With contact "friction" the nodal arrays hold one velocity field per body, one after
    the other: node I of field f is entry f * n_nodes + I (solver/contact.py), and a
    particle's stencil points into its body's field. Everything node by node (the update,
    the conditions, damping) then runs on every field at once."""

    lower: np.ndarray      # (dim,)
    h: np.ndarray          # (dim,) cell sizes
    cells: np.ndarray      # (dim,) int64 cells per axis
    mass: np.ndarray       # (n_nodes,)
    momentum: np.ndarray   # (n_nodes, dim)
    force: np.ndarray      # (n_nodes, dim)
    v_old: np.ndarray      # (n_nodes, dim) v_I^t; the force's array but under USF (`nodal_arrays`)
    v_new: np.ndarray      # (n_nodes, dim) v~_I^{t+dt}, then v_I^{t+dt}
    fields: int = 1        # velocity fields (the arrays hold fields * n_nodes entries)
    inv_h: np.ndarray = field(init=False)
    strides: np.ndarray = field(init=False)
    n_nodes: int = field(init=False)   # nodes of the grid (of one field)

    def __post_init__(self):
        self.inv_h = 1.0 / self.h
        nodes = self.cells + 1
        self.strides = np.concatenate(([1], np.cumprod(nodes)[:-1])).astype(np.int64)
        # once: the contact hook reads it several times a step (np.prod each time cost 0.1-0.2 ms)
        self.n_nodes = int(np.prod(nodes))

    @property
    def node_counts(self) -> np.ndarray:
        return self.cells + 1

    def field_views(self, array: np.ndarray) -> list[np.ndarray]:
        """The contiguous rows of each field in a nodal array."""
        n = self.n_nodes
        return [array[f * n:(f + 1) * n] for f in range(self.fields)]

    def node_positions(self) -> np.ndarray:
        """(n_nodes, dim) coordinates, in node order."""
        axes = [self.lower[a] + self.h[a] * np.arange(self.cells[a] + 1) for a in range(len(self.h))]
        mesh = np.meshgrid(*axes, indexing="ij")
        # node order is x fastest: transpose the 'ij' mesh to (..., z, y, x) before flattening
        return np.stack([m.transpose().ravel() for m in mesh], axis=1)

    def reset(self) -> None:
        self.mass.fill(0.0)
        self.momentum.fill(0.0)
        self.force.fill(0.0)


@dataclass
class Stencil:
    """Per-particle node indices, weights and weight gradients of the shape function."""

    idx: np.ndarray   # (n, nk) int64
    w: np.ndarray     # (n, nk)
    dw: np.ndarray    # (n, nk, dim)


def make_grid(scene) -> Grid:
    cells = np.asarray(scene.grid_shape(), dtype=np.int64)
    fields = scene.grid_fields()
    n_nodes = fields * int(np.prod(cells + 1))
    return Grid(lower=np.asarray(scene.grid_lower(), dtype=np.float64),
                h=np.asarray(scene.cell_sizes(), dtype=np.float64),
                cells=cells, fields=fields, **nodal_arrays(scene, n_nodes))


def v_old_in_force(scene) -> bool:
    """Whether v_I^t is kept in the array of the nodal force f_I: the grid update replaces f_I
    by v_I^t node by node (kernels.integrate_nodes), and nothing reads f_I after the update
    until the next P2G forms it again. USF forms v_I^t before the forces, for its
    stress update, so there each has its own array. A node's 3 values in 3D: 23 bytes a
    particle on MPM3DMP's largest Taylor bar (docs/benchmarks.md, "Memory")."""
    return scene.method.scheme != "usf"


def nodal_arrays(scene, n_nodes: int) -> dict[str, np.ndarray]:
    """The grid's nodal arrays (zeros), n_nodes of them (every velocity field's)."""
    dim = scene.dimension
    force = np.zeros((n_nodes, dim))
    return dict(mass=np.zeros(n_nodes), momentum=np.zeros((n_nodes, dim)), force=force,
                v_old=force if v_old_in_force(scene) else np.zeros((n_nodes, dim)), v_new=np.zeros((n_nodes, dim)))


def grid_geometry(scene) -> Grid:
    """The whole grid's placement and node numbering (lower, h, cells, inv_h, strides), without nodal arrays."""
    empty = np.zeros((0, scene.dimension))
    return Grid(lower=np.asarray(scene.grid_lower(), dtype=np.float64),
                h=np.asarray(scene.cell_sizes(), dtype=np.float64),
                cells=np.asarray(scene.grid_shape(), dtype=np.int64),
                mass=np.zeros(0), momentum=empty, force=empty, v_old=empty, v_new=empty)


def make_stencil(n: int, dim: int, support: int) -> Stencil:
    nk = support**dim
    return Stencil(idx=np.zeros((n, nk), dtype=np.int64), w=np.zeros((n, nk)), dw=np.zeros((n, nk, dim)))


def make_particles(scene) -> tuple[Particles, dict[str, slice]]:
    """Seed every body, sort particles by material, set mass and initial velocity.

    Returns the particles and the slice of particles made of each material.
    """
    dim = scene.dimension
    seeds = seed(scene)
    order = np.argsort(material_of_body(scene)[seeds.body], kind="stable")
    x = np.ascontiguousarray(seeds.position[order])
    body = np.ascontiguousarray(seeds.body[order]).astype(np.int32)
    volume0 = np.ascontiguousarray(seeds.volume[order])
    n = x.shape[0]

    # a gas has no density of its own: its bodies give it
    density = np.array([b.initial_density or scene.materials[b.material].density for b in scene.bodies])
    mass = volume0 * density[body]
    v = np.zeros((n, dim))
    names = ("x", "y", "z")[:dim]
    for b_index, b in enumerate(scene.bodies):
        sel = body == b_index
        if not sel.any():
            continue
        coords = {names[a]: x[sel, a] for a in range(dim)}
        for a, component in enumerate(b.initial_velocity or []):
            if isinstance(component, str):
                v[sel, a] = compile_expression(component, names, scene.expressions).evaluate(**coords)
            elif component is not None:
                v[sel, a] = component

    F = np.zeros((n, dim, dim))
    F[:, np.arange(dim), np.arange(dim)] = 1.0
    particles = Particles(
        x=x, v=v, F=F, L=np.zeros((n, dim, dim)), stress=np.zeros((n, 3, 3)),
        mass=mass, volume=volume0.copy(), volume0=volume0,
        id=np.arange(n, dtype=np.int64), body=body,
    )

    return particles, material_slices(scene, body)


def material_of_body(scene) -> np.ndarray:
    """Index into scene.materials of each body's material (particles are sorted by it)."""
    return np.array([list(scene.materials).index(b.material) for b in scene.bodies], dtype=np.int64)


def material_slices(scene, body: np.ndarray) -> dict[str, slice]:
    """The slice of particles made of each material present, for particles sorted by material."""
    slices: dict[str, slice] = {}
    sorted_material = material_of_body(scene)[body]
    for m_index, name in enumerate(scene.materials):
        where = np.flatnonzero(sorted_material == m_index)
        if where.size:
            slices[name] = slice(int(where[0]), int(where[-1]) + 1)
    return slices


def make_materials(scene, slices: dict[str, slice], particles: Particles) -> list[tuple[object, slice]]:
    models = [(materials.create(scene.materials[name], scene.dimension), sl) for name, sl in slices.items()]
    # the initial stress first: a model may start its state from it (Cam-Clay's p_c); no
    # model that sets its own start stress (a gas) takes an initial_stress
    initial_stress.apply(scene, particles)
    materials.init_particles(models, particles, scene)
    return models
