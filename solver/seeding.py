"""Particle seeding: regular generation ([R] 4.1, VERIFICATION_CASES A.14).

For each body, every grid cell that overlaps the body's bounding box gets
``particles_per_cell`` particles per axis, at (k + 0.5) / ppc of the cell along each
axis; the particles inside the body's geometry are kept. Each particle's volume
is the cell volume divided by ppc**dim.

A body whose geometry is `points` (solver/points.py) is its particles as given:
positions and volumes, no lattice.

Candidates are visited in chunks of bounded size, so memory stays bounded while
counting, and while seeding holds only the kept particles.
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from solver.schema import count_down

if TYPE_CHECKING:
    from solver.scene import Body, Scene

CHUNK = 1 << 18  # candidate points tested at once


@dataclass
class Seeds:
    """The particles of a scene, in body order."""

    position: np.ndarray  # (n, dim) float64, C-contiguous
    volume: np.ndarray  # (n,) float64
    body: np.ndarray  # (n,) int32, index into scene.bodies


def seed(scene: Scene) -> Seeds:
    positions, volumes, bodies = [], [], []
    for index, body in enumerate(scene.bodies):
        given = _given_points(body)
        if given is not None:
            points = given.positions
            volumes.append(given.volumes)
        else:
            kept = [points[inside] for points, inside in _inside_chunks(scene, body)]
            points = np.concatenate(kept) if kept else np.empty((0, scene.dimension))
            volumes.append(np.full(len(points), particle_volume(scene, body)))
        positions.append(points)
        bodies.append(np.full(len(points), index, dtype=np.int32))
    return Seeds(
        position=np.ascontiguousarray(np.concatenate(positions), dtype=np.float64),
        volume=np.concatenate(volumes),
        body=np.concatenate(bodies),
    )


def count_particles(scene: Scene, *, stop_above: int | None = None) -> list[int]:
    """Particles per body, without building the particle arrays.

    With ``stop_above``, counting ends as soon as the total exceeds it (for limit
    checks); the counts are then lower bounds whose sum exceeds ``stop_above``."""
    counts = [0] * len(scene.bodies)
    for index, body in enumerate(scene.bodies):
        given = _given_points(body)
        if given is not None:
            counts[index] = len(given.volumes)
            continue
        for _, inside in _inside_chunks(scene, body, spread=stop_above is not None):
            counts[index] += int(np.count_nonzero(inside))
            if stop_above is not None and sum(counts) > stop_above:
                return counts
    return counts


def _given_points(body: Body):
    """The Points of a body given as particles, else None."""
    return body.geometry.shape() if body.geometry.type == "points" else None


def particle_volume(scene: Scene, body: Body) -> float:
    return math.prod(scene.cell_sizes()) / body.particles_per_cell ** scene.dimension


def box_sides(scene: Scene, body_index: np.ndarray) -> np.ndarray:
    """(n, dim): the sides of the box each particle was seeded as, h / particles_per_cell of
    its body per axis (regular seeding tiles each cell with ppc boxes per axis; a curved
    body's boundary particles keep their whole box). GIMP's boxes and CPDI's domains at t = 0."""
    ppc = np.array([b.particles_per_cell for b in scene.bodies], dtype=np.float64)
    return np.asarray(scene.cell_sizes())[None, :] / ppc[body_index][:, None]


def candidate_cells(scene: Scene, body: Body) -> list[tuple[int, int]]:
    """Per axis, the range [first, stop) of the grid cells that overlap the body's
    bounding box: arithmetic only, whatever the sizes."""
    lower, upper = body.geometry.shape().bounding_box()
    grid_lower, shape, sizes = scene.grid_lower(), scene.grid_shape(), scene.cell_sizes()
    ranges = []
    for a in range(scene.dimension):
        first = max(0, count_down((lower[a] - grid_lower[a]) / sizes[a]))   # an infinite ratio clamps
        stop = min(shape[a], count_down((upper[a] - grid_lower[a]) / sizes[a]) + 1)
        ranges.append((first, max(first, stop)))
    return ranges


def count_candidates(scene: Scene) -> tuple[int, int]:
    """Candidate particles of all bodies (an upper bound of the particles) and the
    point-in-shape tests counting them takes (candidates x the geometry's primitive
    shapes), computed without visiting them: what a limit check decides from."""
    candidates = tests = 0
    for body in scene.bodies:
        given = _given_points(body)
        if given is not None:
            candidates += len(given.volumes)
            continue
        count = math.prod((stop - first) * body.particles_per_cell for first, stop in candidate_cells(scene, body))
        candidates += count
        tests += count * _primitives(body.geometry)
    return candidates, tests


def _primitives(spec) -> int:
    """Boxes, spheres and cylinders in a geometry (each is tested on every candidate)."""
    parts = getattr(spec, "parts", None)
    return 1 if parts is None else sum(_primitives(part) for part in parts)


def candidate_coordinates(scene: Scene, body: Body) -> list[np.ndarray]:
    """Per axis, the candidate particle coordinates: those of the grid cells that
    overlap the body's bounding box. Candidates are their tensor product."""
    grid_lower, sizes = scene.grid_lower(), scene.cell_sizes()
    offsets = (np.arange(body.particles_per_cell) + 0.5) / body.particles_per_cell
    axes = []
    for a, (first, stop) in enumerate(candidate_cells(scene, body)):
        cells = np.arange(first, stop)
        axes.append(grid_lower[a] + (cells[:, None] + offsets).ravel() * sizes[a])
    return axes


def _inside_chunks(scene: Scene, body: Body, spread: bool = False) -> Iterator[tuple[np.ndarray, np.ndarray]]:
    """(candidate points, inside mask) chunk by chunk, in C order of the candidates, or
    with ``spread`` in an order that samples the whole bounding box from the start (so
    that a count stopping at a limit is not spent on the box's empty first rows)."""
    axes = candidate_coordinates(scene, body)
    shape = tuple(len(axis) for axis in axes)
    total = math.prod(shape)
    geometry = body.geometry.shape()
    starts = range(0, total, CHUNK)
    for start in (_spread(starts) if spread else starts):
        index = np.unravel_index(np.arange(start, min(start + CHUNK, total)), shape)
        points = np.stack([axis[i] for axis, i in zip(axes, index)], axis=1)
        yield points, geometry.contains(points)


def _spread(items: range) -> Iterator[int]:
    """Every item once, by a stride coprime with the length (about 0.618 of it)."""
    n = len(items)
    stride = max(1, round(n * 0.618034))
    while math.gcd(stride, n) != 1:
        stride += 1
    for i in range(n):
        yield items[(i * stride) % n]
