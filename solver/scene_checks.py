"""``load_scene``: a scene validated against its schema (solver/scene.py), then checked
against the size limits and the stability limit.

Those checks count the scene's nodes, steps and particles (solver.summary,
solver.seeding) and compare a fixed time step with the waves' (solver.stability),
modules that read the scene's models: they run here, above the schema, so that the
schema imports none of them. Like the scene, this module loads without numba.
"""

import math
from dataclasses import dataclass
from pathlib import Path

from solver.scene import Scene, SceneError, parse_scene
from solver.seeding import count_candidates, count_particles
from solver.stability import time_step_problems
from solver.summary import estimate_steps, memory_limit_problem


@dataclass(frozen=True)
class Limits:
    """Size limits checked by ``load_scene`` (None: unlimited)."""

    max_particles: int | None = None
    max_grid_nodes: int | None = None
    max_steps: int | None = None
    max_memory_bytes: int | None = None   # the estimate of solver.summary.memory_estimate


# What one machine could hold at all: `mpm validate` checks these before counting, so an
# absurd scene (a 1 m grid of 1 nm cells) is refused at once rather than counted for ever.
MACHINE_LIMITS = Limits(max_particles=10**8, max_grid_nodes=10**9)


def load_scene(source: "str | Path | dict | Scene", limits: Limits | None = None,
               files: "str | Path | None" = None, stability: bool = True) -> Scene:
    """Validate a scene given as a path to a JSON file, JSON text, a dict or a Scene.

    `files`: the folder the scene's relative file names (mesh files) start from
    (solver.scene.parse_scene).
    `stability`: refuse a fixed time.dt above the stability limit (solver/stability.py),
    after the limits, so that an absurd scene is refused for its size.

    Raises SceneError listing every problem found."""
    scene = parse_scene(source, files)
    over = _limit_problems(scene, limits) if limits is not None else []
    if over:   # each names the Limits field it is over ("limit"), for the service to name its setting
        raise SceneError([{"path": path, "message": message, "limit": limit} for path, message, limit in over])
    if stability:   # the stability limit reads a sound scene of a size within the limits
        problems = time_step_problems(scene)
        if problems:
            raise SceneError([{"path": path, "message": message} for path, message in problems])
    return scene


# Counting a scene's particles tests each candidate position against each primitive
# shape of its body's geometry; a scene needing more than this many tests per allowed
# particle (a few tenths of a second for the default MPM_MAX_PARTICLES) is refused from
# arithmetic alone, before anything is counted or allocated.
COUNT_FACTOR = 8


def _limit_problems(scene: Scene, limits: Limits) -> list[tuple[str, str, str]]:
    """(path, message, the Limits field) of every limit decided before any loop or allocation
    proportional to the scene's size: nodes and steps from arithmetic, particles from the
    candidates' count (arithmetic), counted only when that is within COUNT_FACTOR times the
    limit; the memory, within those, from the candidates (an upper bound of the particles)."""
    problems = []
    nodes = math.prod(n + 1 for n in scene.grid_shape())
    if limits.max_grid_nodes is not None and nodes > limits.max_grid_nodes:
        problems.append(("grid", f"{nodes} grid nodes, over the limit of {limits.max_grid_nodes}", "max_grid_nodes"))
    if limits.max_steps is not None:
        steps = estimate_steps(scene)
        if steps > limits.max_steps:
            problems.append(("time", f"about {steps} time steps, over the limit of {limits.max_steps}", "max_steps"))
    candidates, tests = count_candidates(scene)
    if limits.max_particles is not None:
        if tests > COUNT_FACTOR * limits.max_particles:
            problems.append(("bodies", f"the bodies' bounding boxes hold {candidates:.3g} candidate particles "
                                       f"(overlapping cells x particles_per_cell^{scene.dimension}), "
                                       f"{tests:.3g} point-in-shape tests with their geometries' parts: more "
                                       f"than {COUNT_FACTOR} x the limit of {limits.max_particles} particles",
                             "max_particles"))
        elif candidates > limits.max_particles:
            if sum(count_particles(scene, stop_above=limits.max_particles)) > limits.max_particles:
                problems.append(("bodies", f"more particles than the limit of {limits.max_particles}",
                                 "max_particles"))
    if limits.max_memory_bytes is not None and not problems:
        memory = memory_limit_problem(scene, candidates, nodes, limits.max_memory_bytes)
        if memory is not None:
            problems.append((*memory, "max_memory_bytes"))
    return problems
