"""Inside-tests of the scene geometries, vectorised over points.

Each geometry answers ``contains(points)`` for an ``(n, dim)`` array (boundary
inclusive) and ``bounding_box()``. ``from_spec`` builds one from the geometry
model of a validated scene (``solver.scene``); it reads only the ``type`` field and
the shape parameters, so this module does not import the scene schema.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

BoundingBox = tuple[np.ndarray, np.ndarray]


class Geometry(Protocol):
    def contains(self, points: np.ndarray) -> np.ndarray: ...

    def bounding_box(self) -> BoundingBox: ...


@dataclass(frozen=True)
class Box:
    lower: np.ndarray
    upper: np.ndarray

    def contains(self, points: np.ndarray) -> np.ndarray:
        return np.all((points >= self.lower) & (points <= self.upper), axis=1)

    def bounding_box(self) -> BoundingBox:
        return self.lower.copy(), self.upper.copy()


@dataclass(frozen=True)
class Sphere:
    """A ball in 3D, a disk in 2D, a segment in 1D."""

    center: np.ndarray
    radius: float

    def contains(self, points: np.ndarray) -> np.ndarray:
        return np.sum((points - self.center) ** 2, axis=1) <= self.radius**2

    def bounding_box(self) -> BoundingBox:
        return self.center - self.radius, self.center + self.radius


@dataclass(frozen=True)
class Cylinder:
    """A 3D circular cylinder along coordinate ``axis``, centred on ``center``."""

    center: np.ndarray
    radius: float
    axis: int
    height: float

    def contains(self, points: np.ndarray) -> np.ndarray:
        offset = points - self.center
        along = offset[:, self.axis]
        across = np.delete(offset, self.axis, axis=1)
        return (np.abs(along) <= 0.5 * self.height) & (np.sum(across**2, axis=1) <= self.radius**2)

    def bounding_box(self) -> BoundingBox:
        half = np.full(self.center.shape, self.radius)
        half[self.axis] = 0.5 * self.height
        return self.center - half, self.center + half


@dataclass(frozen=True)
class Union:
    parts: tuple[Geometry, ...]

    def contains(self, points: np.ndarray) -> np.ndarray:
        inside = self.parts[0].contains(points)
        for part in self.parts[1:]:
            inside |= part.contains(points)
        return inside

    def bounding_box(self) -> BoundingBox:
        boxes = [part.bounding_box() for part in self.parts]
        return np.min([b[0] for b in boxes], axis=0), np.max([b[1] for b in boxes], axis=0)


# Vertices a polygon may have, and all the polygons of a scene together: each inside test
# (seeding, the stability check's samples) loops over the edges, so this bounds its cost.
MAX_POLYGON_VERTICES = 10_000
# Polygons a scene may have: each costs its self-intersection check (a fraction of a
# millisecond for a small one: a union of 4000 triangles took 4.6 s on a loaded machine).
MAX_POLYGONS = 500
# Candidate pairs of edges the self-intersection check (`first_crossing`) tests at most
# (about 0.3 s): outlines have a few per edge, but edges overlapping along both axes (a
# star of thin spikes) make O(n^2), 25 million at 10,000 vertices (8 s). Past it the
# polygon is refused as too complex to check, before any pair is tested.
MAX_CROSSING_PAIRS = 1_000_000


class TooComplex(ValueError):
    """A polygon whose self-intersection check would test more than MAX_CROSSING_PAIRS pairs."""

    def __init__(self, pairs: int):
        super().__init__(f"its edges overlap along both axes so much that checking that it does not "
                         f"intersect itself would test {pairs} pairs of edges, more than {MAX_CROSSING_PAIRS}; "
                         "use fewer vertices, or a union of simpler polygons")
        self.pairs = pairs


# (edge, point) pairs a polygon's inside test handles at once: bounds its temporary arrays
VISITS_AT_ONCE = 1 << 22


def _chunks(counts: np.ndarray, budget: int):
    """Consecutive index ranges of `counts` whose sums stay within `budget` (one item at least)."""
    total = np.cumsum(counts)
    begin = 0
    while begin < len(counts):
        done = total[begin - 1] if begin else 0
        stop = max(begin + 1, int(np.searchsorted(total, done + budget, side="right")))
        yield np.arange(begin, stop)
        begin = stop


@dataclass(frozen=True)
class Polygon:
    """A simple 2D polygon (concave allowed, either orientation), by its vertices.

    The inside test is the even-odd rule, vectorised over the points and the edges: with
    the points sorted by y once, each edge only visits the points in its own y band (a
    `searchsorted` per edge, all at once), so the cost is O(n log n + points in the edges'
    bands), with no Python loop over points or edges (a loop over 10,000 edges was most of
    the 0.8 s a 10,000-vertex polygon took to validate). The crossings are the same
    floating-point expression as an edge-by-edge loop's. Points on an edge may be counted
    either side."""

    vertices: np.ndarray   # (n, 2)

    def contains(self, points: np.ndarray) -> np.ndarray:
        order = np.argsort(points[:, 1], kind="stable")
        x, y = points[order, 0], points[order, 1]
        start, end = self.vertices, np.roll(self.vertices, -1, axis=0)
        sloped = start[:, 1] != end[:, 1]   # a horizontal edge crosses no horizontal ray
        x0, y0, x1, y1 = start[sloped, 0], start[sloped, 1], end[sloped, 0], end[sloped, 1]
        first = np.searchsorted(y, np.minimum(y0, y1), side="left")   # low <= y < high
        counts = np.searchsorted(y, np.maximum(y0, y1), side="left") - first
        crossed = np.zeros(len(points), dtype=np.int64)
        for edges in _chunks(counts, VISITS_AT_ONCE):
            visits = counts[edges]
            edge = np.repeat(edges, visits)
            point = first[edge] + np.arange(visits.sum()) - np.repeat(np.cumsum(visits) - visits, visits)
            crossing = x0[edge] + (y[point] - y0[edge]) * (x1[edge] - x0[edge]) / (y1[edge] - y0[edge])
            crossed += np.bincount(point[x[point] < crossing], minlength=len(points))
        out = np.empty(len(points), dtype=bool)
        out[order] = crossed % 2 == 1
        return out

    def bounding_box(self) -> BoundingBox:
        return self.vertices.min(axis=0), self.vertices.max(axis=0)


def first_crossing(vertices: np.ndarray, chunk: int = 1 << 20,
                   max_pairs: int = MAX_CROSSING_PAIRS) -> tuple[int, int] | None:
    """The first pair of edges (i, j), i < j, of a closed polygon that touch or cross
    although they are not neighbours (edge i runs from vertex i to vertex i + 1), or
    neighbours that fold back onto each other; None for a simple polygon.

    A sweep along x or y (the one with fewer pairs): the edges sorted by their smallest
    coordinate, each paired only with the later ones whose range overlaps its own (a
    `searchsorted`), and those pairs whose boxes overlap tested exactly, `chunk` pairs
    at a time. Near-linear for the outlines scenes have (10,000 vertices on a circle:
    10 ms); at worst (long edges overlapping along both axes) O(n^2) pairs: more than
    `max_pairs` raise TooComplex at once (the count is known before any pair is tested)."""
    p = np.asarray(vertices, dtype=np.float64)
    q = np.roll(p, -1, axis=0)
    n = len(p)
    low, high = np.minimum(p, q), np.maximum(p, q)
    scale = float(np.max(np.abs(p))) or 1.0
    eps = 1e-12 * scale * scale
    if n <= SMALL_POLYGON:   # every pair at once: a sweep's dozen numpy calls cost more than the pairs
        i, j = np.triu_indices(n, 1)
        found = _touching(p, q, i, j, eps)
        return min(found) if found else None
    order, counts = min((_sweep(low[:, a], high[:, a], 1e-12 * scale) for a in (0, 1)), key=lambda s: s[1].sum())
    if counts.sum() > max_pairs:
        raise TooComplex(int(counts.sum()))
    found = []
    start = 0
    while start < n:
        end = start + max(1, int(np.searchsorted(np.cumsum(counts[start:]), chunk, side="right")))
        k = np.repeat(np.arange(start, end), counts[start:end])
        first = np.repeat(np.arange(start, end) + 1 - np.cumsum(np.r_[0, counts[start:end - 1]]), counts[start:end])
        m = np.arange(len(k)) + first
        i, j = np.minimum(order[k], order[m]), np.maximum(order[k], order[m])
        near = np.all((low[i] <= high[j] + 1e-12 * scale) & (low[j] <= high[i] + 1e-12 * scale), axis=1)
        found += _touching(p, q, i[near], j[near], eps)
        start = end
    return min(found) if found else None


# Polygons up to this many vertices are checked on all their pairs of edges (at most 496)
SMALL_POLYGON = 32


def _touching(p: np.ndarray, q: np.ndarray, i: np.ndarray, j: np.ndarray, eps: float) -> list[tuple[int, int]]:
    """The pairs (i, j) of edges that touch and are not neighbours, or neighbours folding back."""
    n = len(p)
    hits = _segments_touch(p[i], q[i], p[j], q[j], eps)
    neighbours = (j == i + 1) | ((i == 0) & (j == n - 1))
    hits &= ~neighbours | _folds_back(p[i], q[i], p[j], q[j], eps)
    return list(zip(i[hits].tolist(), j[hits].tolist()))


def _sweep(low: np.ndarray, high: np.ndarray, tol: float) -> tuple[np.ndarray, np.ndarray]:
    """The edges sorted by `low`, and for each how many later ones start before it ends."""
    order = np.argsort(low, kind="stable")
    stops = np.searchsorted(low[order], high[order] + tol, side="right")
    return order, np.maximum(stops - np.arange(1, len(low) + 1), 0)


def _cross(o, a, b):
    return (a[..., 0] - o[..., 0]) * (b[..., 1] - o[..., 1]) - (a[..., 1] - o[..., 1]) * (b[..., 0] - o[..., 0])


def _on_segment(p, q, r, eps):
    """r on the segment pq, given that the three are collinear."""
    return ((np.minimum(p[..., 0], q[..., 0]) - eps <= r[..., 0]) & (r[..., 0] <= np.maximum(p[..., 0], q[..., 0]) + eps)
            & (np.minimum(p[..., 1], q[..., 1]) - eps <= r[..., 1]) & (r[..., 1] <= np.maximum(p[..., 1], q[..., 1]) + eps))


def _segments_touch(p1, q1, p2, q2, eps):
    d1, d2 = _cross(p2, q2, p1), _cross(p2, q2, q1)
    d3, d4 = _cross(p1, q1, p2), _cross(p1, q1, q2)
    proper = (((d1 > eps) & (d2 < -eps)) | ((d1 < -eps) & (d2 > eps))) & \
             (((d3 > eps) & (d4 < -eps)) | ((d3 < -eps) & (d4 > eps)))
    touch = ((np.abs(d1) <= eps) & _on_segment(p2, q2, p1, eps)) | ((np.abs(d2) <= eps) & _on_segment(p2, q2, q1, eps)) \
        | ((np.abs(d3) <= eps) & _on_segment(p1, q1, p2, eps)) | ((np.abs(d4) <= eps) & _on_segment(p1, q1, q2, eps))
    return proper | touch


def _folds_back(p1, q1, p2, q2, eps):
    """Neighbouring edges that are collinear and point back (a zero-width spike)."""
    d1, d2 = q1 - p1, q2 - p2
    return (np.abs(_cross(p1, q1, q2) + _cross(p2, q2, p1)) <= eps) & (np.abs(d1[..., 0] * d2[..., 1] - d1[..., 1] * d2[..., 0]) <= eps) \
        & ((d1 * d2).sum(axis=-1) < 0)


def _first_and(parts, points: np.ndarray, each) -> np.ndarray:
    """Inside the first part and, for every other part, `each` of inside it."""
    inside = parts[0].contains(points)
    for part in parts[1:]:
        inside &= each(part.contains(points))
    return inside


@dataclass(frozen=True)
class Difference:
    """The first part minus all the others."""

    parts: tuple[Geometry, ...]

    def contains(self, points: np.ndarray) -> np.ndarray:
        return _first_and(self.parts, points, np.logical_not)

    def bounding_box(self) -> BoundingBox:
        return self.parts[0].bounding_box()


@dataclass(frozen=True)
class Intersection:
    parts: tuple[Geometry, ...]

    def contains(self, points: np.ndarray) -> np.ndarray:
        return _first_and(self.parts, points, lambda inside: inside)

    def bounding_box(self) -> BoundingBox:
        """The overlap of the parts' boxes; lower > upper on some axis means empty."""
        boxes = [part.bounding_box() for part in self.parts]
        return np.max([b[0] for b in boxes], axis=0), np.min([b[1] for b in boxes], axis=0)


def from_spec(spec) -> Geometry:
    """Build the geometry of a scene geometry model (``spec.type`` selects the class)."""
    kind = spec.type
    if kind == "box":
        return Box(_vector(spec.lower), _vector(spec.upper))
    if kind == "sphere":
        return Sphere(_vector(spec.center), float(spec.radius))
    if kind == "polygon":
        return Polygon(np.asarray(spec.vertices, dtype=np.float64).reshape(-1, 2))
    if kind in ("mesh", "points"):
        return spec.shape()   # read and checked once, when the scene was validated
    if kind == "cylinder":
        return Cylinder(_vector(spec.center), float(spec.radius), int(spec.axis), float(spec.height))
    parts = tuple(from_spec(part) for part in spec.parts)
    combined = {"union": Union, "difference": Difference, "intersection": Intersection}
    if kind in combined:
        return combined[kind](parts)
    raise ValueError(f"unknown geometry type {kind!r}")


def _vector(values) -> np.ndarray:
    return np.asarray(values, dtype=np.float64)


def ring(x: np.ndarray) -> np.ndarray:
    """2 pi r of each point (x = r in an axisymmetric scene): what a particle's plane volume
    and mass are multiplied by to become the ring it sweeps around the axis."""
    return 2.0 * np.pi * x[:, 0]
