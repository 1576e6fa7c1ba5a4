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
    if kind == "cylinder":
        return Cylinder(_vector(spec.center), float(spec.radius), int(spec.axis), float(spec.height))
    parts = tuple(from_spec(part) for part in spec.parts)
    combined = {"union": Union, "difference": Difference, "intersection": Intersection}
    if kind in combined:
        return combined[kind](parts)
    raise ValueError(f"unknown geometry type {kind!r}")


def _vector(values) -> np.ndarray:
    return np.asarray(values, dtype=np.float64)
