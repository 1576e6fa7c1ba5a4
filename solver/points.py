"""The `points` geometry: a body given as its particles (positions and volumes), inline
or from a CSV or HDF5 file (columns / datasets x, y[, z], volume).

A points body is not a region: seeding takes its particles as they are
(solver/seeding.py), with the volumes given; particles_per_cell does not apply.
"""
from __future__ import annotations

import io
import os
from dataclasses import dataclass

import numpy as np

from solver.mesh import GeometryFileError, read_file

FORMATS = {".csv": "csv", ".h5": "hdf5", ".hdf5": "hdf5"}
AXES = ("x", "y", "z")


class PointsError(GeometryFileError):
    """A points file or list that cannot be a body (the message says why)."""


@dataclass(frozen=True, eq=False)
class Points:
    positions: np.ndarray   # (n, dim)
    volumes: np.ndarray     # (n,)

    def bounding_box(self):
        return self.positions.min(axis=0), self.positions.max(axis=0)

    def contains(self, points: np.ndarray) -> np.ndarray:
        raise TypeError("a points geometry is not a region: its particles are seeded as given")


def from_lists(positions: list, volumes: list) -> Points:
    if len(positions) != len(volumes):
        raise PointsError(f"{len(positions)} positions but {len(volumes)} volumes")
    return Points(np.asarray(positions, dtype=np.float64), np.asarray(volumes, dtype=np.float64))


def from_file(path: str, limit: int) -> Points:
    """The points of a CSV file (a header row naming x, y[, z] and volume, in any order)
    or an HDF5 file (1D datasets of those names)."""
    kind = FORMATS.get(os.path.splitext(path)[1].lower())
    if kind is None:
        raise PointsError(f"{path!r}: a points file is .csv, .h5 or .hdf5")
    raw = read_file(path, limit, kind="points")
    columns = _csv_columns(raw) if kind == "csv" else _hdf5_columns(raw)
    axes = [name for name in AXES if name in columns]
    if "volume" not in columns or axes != list(AXES[:len(axes)]) or len(axes) < 1:
        raise PointsError(f"{path!r} needs columns x, y[, z] and volume; it has {sorted(columns)}")
    positions = np.stack([columns[name] for name in axes], axis=1)
    volumes = columns["volume"]
    if not (np.all(np.isfinite(positions)) and np.all(np.isfinite(volumes))):
        raise PointsError(f"{path!r} has values that are not finite numbers")
    if len(volumes) == 0:
        raise PointsError(f"{path!r} has no points")
    if np.any(volumes <= 0):
        raise PointsError(f"{path!r}: volume must be > 0 (row {int(np.argmax(volumes <= 0)) + 1} is not)")
    return Points(np.ascontiguousarray(positions), np.ascontiguousarray(volumes))


def _csv_columns(raw: bytes) -> dict[str, np.ndarray]:
    text = raw.decode("utf-8", errors="replace")
    header, _, body = text.partition("\n")
    names = [name.strip().lower() for name in header.split(",")]
    try:
        table = np.loadtxt(io.StringIO(body), delimiter=",", ndmin=2, dtype=np.float64)
    except ValueError as exc:
        raise PointsError(f"the CSV file has a value that is not a number: {exc}") from None
    if table.size and table.shape[1] != len(names):
        raise PointsError(f"the CSV header names {len(names)} columns, the rows have {table.shape[1]}")
    return {name: table[:, k] if table.size else np.empty(0) for k, name in enumerate(names)}


def _hdf5_columns(raw: bytes) -> dict[str, np.ndarray]:
    import h5py

    try:
        with h5py.File(io.BytesIO(raw), "r") as handle:
            return {name: np.asarray(handle[name], dtype=np.float64).ravel()
                    for name in (*AXES, "volume") if name in handle}
    except OSError as exc:
        raise PointsError(f"is not a readable HDF5 file: {exc}") from None
