"""What a scene will cost, computed before anything proportional to it is allocated.

Particles are counted chunk by chunk (solver.seeding); everything else is
arithmetic on the scene. The step count of an adaptive run, the memory and the
run time are estimates: the time step follows the waves and velocities as they
evolve, and the run time comes from a cost model measured on this machine
(solver/cost.py).
"""

from __future__ import annotations

import math

import numpy as np
from pydantic import BaseModel, Field

from solver import capabilities, cost, materials, stability
from solver import shape as shape_functions
from solver.materials.ideal_gas import grid_density
from solver.pore_fluid_schema import saturated
from solver.scene import Scene
from solver.schema import count_up
from solver.series import MAX_SERIES_POINTS
from solver.seeding import count_particles
from solver.state import v_old_in_force


class Summary(BaseModel):
    particles: int = Field(description="number of particles, all bodies")
    particles_per_body: list[int] = Field(description="particles of each body, in scene order")
    grid_shape: list[int] = Field(description="grid cells per axis")
    grid_nodes: int = Field(description="grid nodes: product of (cells + 1) over the axes")
    dt: float = Field(description="the fixed time step, or an estimate of the adaptive one at t = 0")
    estimated_steps: int = Field(description="end / dt; an estimate when dt is adaptive")
    memory_bytes: int = Field(description="estimate of the run's peak resident memory: the process, its particle "
                                          "and grid arrays, its output (solver/summary.py memory_bytes)")
    estimated_run_seconds: float = Field(description="wall time from start to exit, from this machine's measured "
                                                     "cost model (solver/cost.py; mpm calibrate), compilation "
                                                     "included")
    estimated_compile_seconds: float = Field(0.0, description="of which compiling the kernels of a variant not "
                                                              "in this machine's kernel cache (0 when it is)")
    warnings: list[dict[str, str]] = Field(default_factory=list,
                                           description="[{path, message}]: valid, but probably not what is meant")


def summarize(scene: Scene) -> Summary:
    per_body = count_particles(scene)
    particles = sum(per_body)
    shape = scene.grid_shape()
    nodes = math.prod(n + 1 for n in shape)
    dt = time_step(scene)
    steps = estimate_steps(scene)
    compiling = cost.compile_seconds(scene, cost.planned_threads(scene, particles))
    return Summary(
        particles=particles,
        particles_per_body=per_body,
        grid_shape=list(shape),
        grid_nodes=nodes,
        dt=dt,
        estimated_steps=steps,
        memory_bytes=memory_bytes(scene, particles, nodes),
        estimated_run_seconds=cost.estimate_seconds(scene, per_body, nodes, steps) + compiling,
        estimated_compile_seconds=compiling,
        warnings=[{"path": path, "message": message} for path, message in scene_warnings(scene)],
    )


# Elastic solids, whose free vibrations the PIC share of the FLIP blend damps.
_VIBRATING = {"linear_elastic", "neo_hookean"}
# Energy a free vibration loses per period at flip_ratio 0.99 (benchmarks/flip_damping.py, docs/scene.md).
FLIP_099_LOSS = {"bar": "1.2 %", "beam": "7.6 %"}


def scene_warnings(scene: Scene) -> list[tuple[str, str]]:
    """(path, message) of what is valid but probably not meant: today a FLIP blend below 1 on an
    elastic body that runs for at least one period of its slowest axial wave, with no damping
    asked for (then the blend's damping is a surprise)."""
    method = scene.method
    if method.transfer != "flip" or method.flip_ratio >= 1.0 or scene.damping is not None:
        return []
    for body in scene.bodies:
        material = scene.materials[body.material]
        speed = material.initial_wave_speed(body)
        if material.model not in _VIBRATING or speed <= 0:
            continue
        lower, upper = body.geometry.shape().bounding_box()
        if scene.time.end >= 4 * float(max(np.subtract(upper, lower))) / speed:
            return [("method.flip_ratio",
                     f"{method.flip_ratio:g} blends {100 * (1 - method.flip_ratio):.3g} % PIC into every step, which "
                     f"damps vibrations: at 0.99 a coarse cantilever lost {FLIP_099_LOSS['beam']} of its energy a "
                     f"period, a bar {FLIP_099_LOSS['bar']} (docs/scene.md, method); 1.0 keeps them, and "
                     f"`damping` says that damping is meant")]
    return []


def time_step(scene: Scene) -> float:
    """The fixed dt, or cfl * min(h) / max over bodies (wave speed + largest initial
    speed) for an adaptive run, and at most cfl times the conduction limit where heat
    conducts (solver/thermal_schema.py). Where nothing moves, carries waves or conducts, end."""
    if scene.time.dt is not None:
        return scene.time.dt
    limit = stability.stable_limit(scene)   # the waves' and, where heat conducts, the conduction's
    return scene.time.end if limit is None else scene.time.cfl * limit.dt


def estimate_steps(scene: Scene) -> int:
    fixed = scene.time.fixed_steps()
    if fixed is not None:
        return fixed
    dt = time_step(scene)
    return max(1, count_up(scene.time.end / dt if dt > 0 else math.inf))   # dt underflowed: no end in sight


# The transfers that keep C_p (solver/transfer.py TRANSFERS; that module is numba's).
_AFFINE_TRANSFERS = ("apic", "mls")
# What a solver process holds before its scene's arrays: python, numpy, numba, h5py and the
# step's compiled kernels (benchmarks/memory.py: a run's peak less its arrays, 35 k to 3 M particles).
PROCESS_BASELINE_BYTES = 230 * 2**20
# Resident bytes a point of the preview takes while matplotlib draws it (3D scatter; the
# sim's arrays are gone by then, solver/runner.py): benchmarks/memory.py.
_PREVIEW_POINT_BYTES = 600


def memory_bytes(scene: Scene, particles: int, nodes: int) -> int:
    """The run's peak resident memory: each process's baseline, plus memory_estimate's parts
    held at once while stepping, or the preview's drawing after them where that is more."""
    from solver.results import MAX_PREVIEW_POINTS   # (h5py: not for the scene's other figures)

    held = sum(memory_estimate(scene, particles, nodes).values())
    preview = _PREVIEW_POINT_BYTES * min(particles, MAX_PREVIEW_POINTS)
    return PROCESS_BASELINE_BYTES * scene.parallel.processes + max(held, preview)


def particle_bytes(scene: Scene) -> int:
    """Bytes per particle of the arrays the solver keeps for it (solver/state.py Particles):
    8-byte position, velocity (dim each), F and L (dim^2, 3x3 axisymmetric), stress (9),
    mass, volume, volume0, id; the 4-byte body index; the materials' declared state
    (solver/materials/registry.py state_values); the reference position where TLMPM, a
    body force or the `reference_position` output field needs it (and TLMPM's first Piola stress); C_p of APIC and MLS; the fused
    backend's v_pic of MUSL's remap (allocated for any scheme), or the general backend's
    stored stencil: the weights, weight gradients and node indices of the nodes it touches;
    a saturated soil's pore pressure, Darcy flux and three fluid constants (solver/pore_fluid.py),
    and on the fused backend the step's first positions its passes form their weights at; the
    stencil of a gas that takes its density from the grid (solver/gas_density.py), on either backend."""
    from solver.loads import keeps_reference_position

    dim = scene.dimension
    tensor = 9 if scene.axisymmetric else dim * dim
    values = 2 * dim + 2 * tensor + 9 + 4 + materials.state_values(scene)
    if keeps_reference_position(scene):
        values += dim
    if scene.method.formulation == "tlmpm":   # its first Piola stress
        values += tensor
    if scene.method.transfer in _AFFINE_TRANSFERS:
        values += dim * dim
    fused = cost.backend_name(scene) == "fused"
    if saturated(scene):
        values += 4 + dim + (dim if fused else 0)
    touched = shape_functions.REGISTRY[scene.method.shape_function].support ** dim
    if fused:
        values += dim
    stencil = touched * (1 + dim) + touched
    values += stencil * ((not fused) + grid_density(scene))   # the stored one; a gas's own (solver/gas_density.py)
    return 8 * values + 4


def node_bytes(scene: Scene, threads: int) -> int:
    """Bytes per grid node (of one velocity field): mass, momentum, force, v_old (but where it is
    kept in the force's array, solver/state.py v_old_in_force) and v_new, the copies of mass,
    momentum and force each thread beyond the first adds into (solver/threads.py ScatterCopies),
    the domain's 1-byte mask of active nodes; with contact "friction" each body's field and its
    presence and normal (1 + dim); a saturated soil's six nodal values (solver/pore_fluid.py
    PoreFluid.place); a gas's nodal mass and volume where it takes its density from the grid
    (solver/gas_density.py)."""
    dim = scene.dimension
    velocities = 1 if v_old_in_force(scene) else 2
    per_field = 8 * (1 + (2 + velocities) * dim) + 8 * (threads - 1) * (1 + 2 * dim) \
        + (8 * 6 if saturated(scene) else 0) + (8 * 2 if grid_density(scene) else 0)
    return scene.grid_fields() * (per_field + (8 * (1 + dim) if scene.contact.fields else 0)) + 1


# Values per particle of an output field in a frame (solver/fields.py); 1 for the scalars.
_FRAME_FIELD_WIDTH = {"position": "dim", "velocity": "dim", "stress": 6, "deformation_gradient": "dim2",
                      "reference_position": "dim"}
# Output fields one process writes from the state's own arrays (no copy); the others are formed for the frame.
_FRAME_VIEWS = {"position", "velocity", "deformation_gradient", "mass", "volume", "reference_position"}
_BODY_BYTES = 4096          # a body's own objects (its geometry, material, expressions), roughly
_FRAME_BYTES = 256          # a frame's bookkeeping (its HDF5 group and attributes in the writer)
_SERIES_VALUE_BYTES = 16    # a buffered row's float and its dataset value


def memory_estimate(scene: Scene, particles: int, nodes: int) -> dict[str, int]:
    """The bytes a run's scene makes it hold at once, by the scene path that makes them (what
    a limit error names): arithmetic on the scene, nothing allocated. "bodies" is the particle
    arrays (particle_bytes) and each body's own objects, "grid" the grid's arrays (node_bytes,
    on the threads the run will take), "output.frames" what a frame forms (one process: the
    widest field it derives, as the writer takes the fields one at a time, a field of each
    particle's own state a block of rows at a time, e.g. the stress's six components; several:
    the frame gathered on rank 0)
    and every frame's bookkeeping, "output.series" the energy and `output.series` rows (one
    column per body and axis for momentum and center_of_mass)."""
    dim = scene.dimension
    widths = {"dim": dim, "dim2": dim * dim}
    field_widths = {name: widths.get(w, w) for name, w in
                    ((name, _FRAME_FIELD_WIDTH.get(name, 1)) for name in scene.output.fields)}
    if scene.parallel.processes > 1:
        frame = 2 * 8 * (3 + sum(field_widths.values())) * particles
    else:
        frame = 8 * max((w * (min(particles, capabilities.ROW_BLOCK) if name in capabilities.ROW_LOCAL_FIELDS
                              else particles)
                         for name, w in field_widths.items() if name not in _FRAME_VIEWS), default=0)
    steps = estimate_steps(scene)
    energies = scene.output.energies
    if energies is False:
        rows = 0
    else:
        stride = max(1, count_up(steps / MAX_SERIES_POINTS)) if energies is True else int(energies)
        rows = steps // stride + 2
    per_body_columns = {"momentum": dim, "center_of_mass": dim}
    columns = 8 + sum(per_body_columns.get(name, 0) * len(scene.bodies) for name in scene.output.series) \
        + dim * (len(scene.boundary_conditions) + len(scene.bodies)) * ("reactions" in scene.output.series)
    threads = cost.planned_threads(scene, particles)
    return {"bodies": particles * particle_bytes(scene) + _BODY_BYTES * len(scene.bodies),
            "grid": nodes * node_bytes(scene, threads),
            "output.frames": frame + _FRAME_BYTES * scene.output.frames,
            "output.series": _SERIES_VALUE_BYTES * rows * columns}


def memory_limit_problem(scene: Scene, particles: int, nodes: int, limit: int) -> tuple[str, str] | None:
    """(the path of the largest part, why) when the estimate is over `limit`, else None."""
    parts = memory_estimate(scene, particles, nodes)
    total = sum(parts.values())
    if total <= limit:
        return None
    largest = max(parts, key=parts.get)
    shown = ", ".join(f"{path} {_gib(size)}" for path, size in parts.items())
    return largest, (f"the run would need about {_gib(total)} of memory ({shown}), over the limit of "
                     f"{_gib(limit)}; {largest} takes the most")


def _gib(size: int) -> str:
    return f"{size / 2**30:.3g} GiB"


def empty_bodies(scene: Scene, per_body: list[int]) -> list[tuple[str, str]]:
    """(path, why) of each body that seeds no particle (it lies between the particle
    positions of its cells, or its cells are huge), and of a scene with none at all."""
    problems = [(f"bodies[{i}]", f"body {body.name!r} seeds no particle: no particle position of its cells "
                                 f"(particles_per_cell = {body.particles_per_cell} per axis) falls inside its "
                                 "geometry; make it larger than a cell, or the cells smaller")
                for i, (body, count) in enumerate(zip(scene.bodies, per_body)) if count == 0]
    listed = problems[:MAX_LISTED]   # thousands of empty bodies: an answer of a few lines, not megabytes
    if len(problems) > MAX_LISTED:
        listed.append(("bodies", f"and {len(problems) - MAX_LISTED} more bodies seed no particle"))
    if per_body and len(problems) == len(per_body) and len(problems) > 1:
        listed.append(("bodies", "no body seeds a particle: the scene has nothing to simulate"))
    return listed


MAX_LISTED = 20   # empty bodies named one by one
