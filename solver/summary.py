"""What a scene will cost, computed before anything proportional to it is allocated.

Particles are counted chunk by chunk (solver.seeding); everything else is
arithmetic on the scene. The step count of an adaptive run, the memory and the
run time are estimates: the time step follows the waves and velocities as they
evolve, and the throughput depends on the machine.
"""

from __future__ import annotations

import math

import numpy as np
from pydantic import BaseModel, Field

from solver import shape as shape_functions
from solver.expressions import compile_expression
from solver.scene import SPACE_VARIABLES, TIME_VARIABLES, Body, Scene
from solver.seeding import count_particles
from solver.thermal_schema import conduction_time_step

# Assumed solver throughput in particle-steps per second (one process): a rough
# figure for the order of magnitude of the run time, not a measurement.
THROUGHPUT = {1: 1e7, 2: 1e7, 3: 3e6}

_SAMPLES_PER_AXIS = 9  # points per axis of a body's box where initial velocities are sampled
_TIME_SAMPLES = 101  # instants in [0, end] where prescribed velocities are sampled


class Summary(BaseModel):
    particles: int = Field(description="number of particles, all bodies")
    particles_per_body: list[int] = Field(description="particles of each body, in scene order")
    grid_shape: list[int] = Field(description="grid cells per axis")
    grid_nodes: int = Field(description="grid nodes: product of (cells + 1) over the axes")
    dt: float = Field(description="the fixed time step, or an estimate of the adaptive one at t = 0")
    estimated_steps: int = Field(description="end / dt; an estimate when dt is adaptive")
    memory_bytes: int = Field(description="estimate of the solver's particle and grid arrays")
    estimated_run_seconds: float = Field(description="rough estimate from an assumed throughput")


def summarize(scene: Scene) -> Summary:
    per_body = count_particles(scene)
    particles = sum(per_body)
    shape = scene.grid_shape()
    nodes = math.prod(n + 1 for n in shape)
    dt = time_step(scene)
    steps = estimate_steps(scene)
    return Summary(
        particles=particles,
        particles_per_body=per_body,
        grid_shape=list(shape),
        grid_nodes=nodes,
        dt=dt,
        estimated_steps=steps,
        memory_bytes=memory_bytes(scene, particles, nodes),
        estimated_run_seconds=particles * steps / THROUGHPUT[scene.dimension],
    )


def time_step(scene: Scene) -> float:
    """The fixed dt, or cfl * min(h) / max over bodies (wave speed + largest initial
    speed) for an adaptive run, and at most cfl times the conduction limit where heat
    conducts (solver/thermal_schema.py). Where nothing moves, carries waves or conducts, end."""
    if scene.time.dt is not None:
        return scene.time.dt
    fastest = max(_wave_speed(scene, body) + _largest_speed(scene, body) for body in scene.bodies)
    dt = scene.time.end if fastest <= 0 else scene.time.cfl * min(scene.cell_sizes()) / fastest
    conduction = conduction_time_step(scene)
    return dt if conduction is None else min(dt, scene.time.cfl * conduction[0])


def estimate_steps(scene: Scene) -> int:
    fixed = scene.time.fixed_steps()
    if fixed is not None:
        return fixed
    return max(1, math.ceil(scene.time.end / time_step(scene)))


def memory_bytes(scene: Scene, particles: int, nodes: int) -> int:
    """8-byte values per particle: position, velocity (dim each), F and L (dim^2
    each), stress (9), mass, volume, volume0, density, id, the weights and weight
    gradients of the nodes it touches and their indices; 4 bytes for the body
    index. Per node: mass, two momenta and force (dim each); with contact "friction" that per
    body, and each body's presence and normal (1 + dim)."""
    dim = scene.dimension
    touched = shape_functions.REGISTRY[scene.method.shape_function].support ** dim
    per_particle = 8 * (2 * dim + 2 * dim * dim + 9 + 4 + 1 + touched * (1 + dim) + touched) + 4
    per_node = 8 * (1 + 3 * dim) + (8 * (1 + dim) if scene.contact.fields else 0)
    return particles * per_particle + nodes * per_node * scene.grid_fields()


def _wave_speed(scene: Scene, body: Body) -> float:
    return scene.materials[body.material].initial_wave_speed(body)


def _largest_speed(scene: Scene, body: Body) -> float:
    """Largest initial (or prescribed) speed, sampled on a lattice over the body's
    box (or over [0, end] for a prescribed velocity)."""
    if body.velocity is not None:
        values = {"t": np.linspace(0.0, scene.time.end, _TIME_SAMPLES)}
        return _largest_norm(body.velocity, TIME_VARIABLES, values)
    if body.initial_velocity is None:
        return 0.0
    lower, upper = body.geometry.shape().bounding_box()
    lattice = np.meshgrid(*(np.linspace(lo, up, _SAMPLES_PER_AXIS) for lo, up in zip(lower, upper)), indexing="ij")
    values = {name: axis.ravel() for name, axis in zip(SPACE_VARIABLES, lattice)}
    return _largest_norm(body.initial_velocity, SPACE_VARIABLES, values)


def _largest_norm(components: list[float | str], variables: tuple[str, ...], values: dict) -> float:
    squares = 0.0
    for component in components:
        if component is None:   # a free axis of a rigid body
            continue
        value = compile_expression(component, variables).evaluate(**values) if isinstance(component, str) else component
        squares = squares + np.square(value)
    largest = float(np.max(np.sqrt(squares)))
    return largest if math.isfinite(largest) else 0.0
