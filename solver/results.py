"""The result file: ``result.h5`` (layout of INTERFACES.md) and its XDMF sidecar.

The run loop owns one :class:`ResultWriter` per run::

    with ResultWriter(out_dir, scene, solver_version) as writer:
        writer.write_frame(step, time, fields)      # each output frame
        writer.append_series(time=t, dt=dt, ...)    # each logged step
        writer.close("partial")                     # only when the run did not finish

Leaving the ``with`` block normally closes the file as ``"complete"``; leaving
it by an exception closes it as ``"partial"``. Every frame is flushed to disk
when written, so a killed process keeps the frames written so far (with
``status = "partial"``, the value the file carries until it is closed).

The readers (:func:`list_frames`, :func:`read_frame`, :func:`read_series`)
open the file without HDF5 file locking, so the service can read a file that
a running job is still writing.
"""
from __future__ import annotations

import itertools
import json
import math
import os
import tempfile
import xml.etree.ElementTree as ET
from pathlib import Path
from collections.abc import Mapping
from typing import Any

import h5py
import numpy as np

from solver.errors import SolverError

FORMAT = "mpm-result"
FORMAT_VERSION = 1
RESULT_FILE = "result.h5"
XDMF_FILE = "result.xdmf"
STATUSES = ("complete", "partial")

# Per-particle fields every frame carries (INTERFACES.md); the rest are the
# fields the scene asked for.
REQUIRED_FIELDS = ("id", "body", "mass", "position")
INTEGER_DTYPES = {"id": np.int64, "body": np.int32}
# Helper arrays for the XDMF sidecar, written at close: the vertex list of the
# Polyvertex topology (0, 1, 2, ...) per particle count, and for 1D results the
# positions padded with zeros to x, y, z per frame: XDMF has no one-coordinate
# geometry, and ParaView's XDMF3 reader reads neither X_Y_Z nor HyperSlab items.
XDMF_GROUP = "xdmf"


class ResultWriter:
    """Writes ``out_dir/result.h5`` frame by frame and ``out_dir/result.xdmf`` at close.

    ``scene`` is the validated :class:`solver.scene.Scene` (anything with
    ``model_dump_json()`` and ``dimension``).
    """

    def __init__(self, out_dir: str | os.PathLike, scene: Any, solver_version: str) -> None:
        self.out_dir = Path(out_dir)
        self.out_dir.mkdir(parents=True, exist_ok=True)
        self.path = self.out_dir / RESULT_FILE
        self.xdmf_path = self.out_dir / XDMF_FILE
        self.dimension = int(scene.dimension)
        self.frame_count = 0
        self._series_rows: list[dict[str, float]] = []
        self.series_count = 0  # rows of the time series so far (written and buffered)
        self._closed = False
        # No file lock: readers (preview, service) may open the file while it grows.
        self._file = h5py.File(self.path, "w", locking=False)
        attrs = self._file.attrs
        attrs["format"] = FORMAT
        attrs["format_version"] = FORMAT_VERSION
        attrs["scene"] = scene.model_dump_json()
        attrs["dimension"] = self.dimension
        attrs["solver_version"] = str(solver_version)
        attrs["status"] = "partial"
        self._file.create_group("frames")
        self._file.create_group("time_series")
        self._file.flush()

    def __enter__(self) -> ResultWriter:
        return self

    def __exit__(self, exc_type, exc, tb) -> None:
        if not self._closed:
            self.close("complete" if exc_type is None else "partial")

    # -- frames ------------------------------------------------------------

    def write_frame(self, step: int, time: float, fields: Mapping[str, np.ndarray]) -> str:
        """Write one snapshot as ``/frames/NNNNNN`` and flush; returns the group name.

        The fields are read and written one at a time: a mapping that forms each field as it is
        read (solver/fields.py FrameFields) has one formed field alive at once, not the frame, and
        where it gives a field by `blocks` (first row, values), a block of it. A bad field leaves
        no frame behind (the group is removed before the error is raised)."""
        self._check_open()
        missing = [key for key in REQUIRED_FIELDS if key not in fields]
        if missing:
            raise ValueError(f"frame is missing the required field(s) {', '.join(missing)}")
        name = f"{self.frame_count:06d}"
        group = self._file["frames"].create_group(name)
        try:
            count = None
            for key in fields:
                count = self._write_field(group, key, fields, count)
        except ValueError:
            del self._file["frames"][name]
            raise
        # The attrs go last: readers take a frame without them as still being written.
        group.attrs["time"] = float(time)
        group.attrs["step"] = int(step)
        self.frame_count += 1
        self._flush_series()
        self._file.flush()
        return name

    def _write_field(self, group, key: str, fields, count: int | None) -> int:
        """Write field `key` of `fields` as a dataset of `group`, by blocks of rows where the
        mapping gives them (`blocks`); returns its rows (`count`: those of the fields before it)."""
        blocks = fields.blocks(key) if hasattr(fields, "blocks") else iter([(0, fields[key])])
        _, first = next(blocks)
        following = next(blocks, None)
        if following is None:   # the whole field at once
            array = self._checked_field(key, first, count)
            group.create_dataset(key, data=array)
            return array.shape[0]
        if count is None:
            raise ValueError(f"field {key!r} comes in blocks before a field that gives the particle count")
        array = self._checked_field(key, first, None)
        dataset = group.create_dataset(key, shape=(count,) + array.shape[1:], dtype=array.dtype)
        written = 0
        for start, values in itertools.chain([(0, first), following], blocks):
            array = self._checked_field(key, values, None)
            if start != written or written + array.shape[0] > count:
                raise ValueError(f"field {key!r} has more than {count} rows (one per particle)")
            dataset[start:start + array.shape[0]] = array
            written += array.shape[0]
            del array, values   # (before the next block is formed)
        if written != count:
            raise ValueError(f"field {key!r} has {written} rows, expected {count} (one per particle)")
        return count

    def _checked_field(self, key: str, value, count: int | None) -> np.ndarray:
        """The field as written (contiguous, its dtype); `count`: the rows of the fields before it."""
        if not key or "/" in key:
            raise ValueError(f"invalid field name {key!r}")
        array = np.ascontiguousarray(value, dtype=INTEGER_DTYPES.get(key, np.float64))
        if array.ndim == 0:
            raise ValueError(f"field {key!r} must have one row per particle, got a scalar")
        if count is not None and array.shape[0] != count:
            raise ValueError(f"field {key!r} has {array.shape[0]} rows, expected {count} (one per particle)")
        rows = array.shape[0]
        expected = {"id": (rows,), "body": (rows,), "mass": (rows,), "position": (rows, self.dimension),
                    "velocity": (rows, self.dimension), "stress": (rows, 6)}.get(key)
        if expected is not None and array.shape != expected:
            raise ValueError(f"field {key!r} has shape {array.shape}, expected {expected}")
        return array

    # -- time series -------------------------------------------------------

    def append_series(self, **values: float) -> None:
        """Buffer one row of the time series (``time``, ``dt``, energies, ...).

        A key that first appears in a later row gets NaN for the earlier rows,
        so every ``/time_series`` dataset has one value per row.
        """
        self._check_open()
        row: dict[str, float] = {}
        for key, value in values.items():
            if not key or "/" in key:
                raise ValueError(f"invalid time-series name {key!r}")
            row[key] = float(value)
        self._series_rows.append(row)
        self.series_count += 1

    def series(self) -> dict[str, np.ndarray]:
        """The time series so far (written and buffered), ``{name: array}``."""
        self._flush_series()
        return {key: dataset[()] for key, dataset in self._file["time_series"].items()}

    def copy_frames(self, source: str | os.PathLike, count: int) -> None:
        """Start with the first ``count`` frames of another result file (a resumed run)."""
        self._check_open()
        with open_result(source) as h5:
            for name in _complete_frames(h5)[:count]:
                h5.copy(h5["frames"][name], self._file["frames"], name=name)
        self.frame_count = count
        self._file.flush()

    def _flush_series(self) -> None:
        if not self._series_rows:
            return
        group = self._file["time_series"]
        keys = {key for row in self._series_rows for key in row} | set(group.keys())
        written = max((group[key].shape[0] for key in group), default=0)
        new = len(self._series_rows)
        for key in sorted(keys):
            if key not in group:
                dataset = group.create_dataset(
                    key, shape=(written,), maxshape=(None,), dtype=np.float64,
                    chunks=(1024,), fillvalue=np.nan,
                )
            else:
                dataset = group[key]
            dataset.resize((written + new,))
            dataset[written:] = [row.get(key, math.nan) for row in self._series_rows]
        self._series_rows.clear()

    # -- closing -----------------------------------------------------------

    def close(self, status: str = "complete") -> None:
        """Write the status and the buffered series, close the file, write the XDMF sidecar."""
        if status not in STATUSES:
            raise ValueError(f"status must be one of {STATUSES}, got {status!r}")
        if self._closed:
            return
        try:
            self._flush_series()
            self._write_xdmf_helpers()
            self._file.attrs["status"] = status
            self._file.flush()
            xdmf = xdmf_document(self._file, self.path.name)
        finally:
            self._file.close()
            self._closed = True
        _write_atomically(self.xdmf_path, xdmf)

    def _write_xdmf_helpers(self) -> None:
        frames = self._file["frames"]
        names = _complete_frames(self._file)
        helpers = self._file.create_group(XDMF_GROUP)
        for count in sorted({frames[name]["position"].shape[0] for name in names}):
            helpers.create_dataset(f"vertices_{count}", data=np.arange(count, dtype=np.int64))
        if self.dimension == 1:
            for name in names:
                x = frames[name]["position"][:, 0]
                helpers.create_dataset(f"xyz_{name}", data=np.column_stack([x, 0 * x, 0 * x]))

    def _check_open(self) -> None:
        if self._closed:
            raise RuntimeError(f"{self.path} is already closed")


# -- XDMF ------------------------------------------------------------------


def xdmf_document(h5: h5py.File, h5_name: str) -> str:
    """The XDMF 3 text describing every complete frame of an open result file.

    One temporal collection of Polyvertex grids (one per frame); datasets are
    referenced as ``h5_name:/frames/NNNNNN/field``, relative to the sidecar.
    """
    dimension = int(h5.attrs["dimension"])
    root = ET.Element("Xdmf", Version="3.0")
    domain = ET.SubElement(root, "Domain")
    collection = ET.SubElement(
        domain, "Grid", Name="particles", GridType="Collection", CollectionType="Temporal"
    )
    for name in _complete_frames(h5):
        frame = h5["frames"][name]
        count = frame["position"].shape[0]
        grid = ET.SubElement(collection, "Grid", Name=f"frame_{name}", GridType="Uniform")
        ET.SubElement(grid, "Time", Value=repr(float(frame.attrs["time"])))
        topology = ET.SubElement(
            grid, "Topology", TopologyType="Polyvertex",
            NumberOfElements=str(count), NodesPerElement="1",
        )
        _data_item(topology, h5_name, h5[XDMF_GROUP][f"vertices_{count}"])
        _geometry(grid, h5_name, frame, dimension)
        for key in sorted(frame):
            if key != "position":
                _attributes(grid, h5_name, frame[key], dimension)
    ET.indent(root)
    return '<?xml version="1.0" encoding="utf-8"?>\n' + ET.tostring(root, encoding="unicode") + "\n"


def _geometry(grid: ET.Element, h5_name: str, frame: h5py.Group, dimension: int) -> None:
    if dimension == 1:
        position = frame.file[XDMF_GROUP][f"xyz_{frame.name.rsplit('/', 1)[-1]}"]
    else:
        position = frame["position"]
    geometry = ET.SubElement(grid, "Geometry", GeometryType="XY" if dimension == 2 else "XYZ")
    _data_item(geometry, h5_name, position)


def _attributes(grid: ET.Element, h5_name: str, dataset: h5py.Dataset, dimension: int) -> None:
    """One XDMF attribute per field: scalar, vector (dim columns) or matrix (the rest)."""
    name = dataset.name.rsplit("/", 1)[-1]
    shape = dataset.shape
    if len(shape) == 1 or (len(shape) == 2 and shape[1] == 1):
        attribute = ET.SubElement(grid, "Attribute", Name=name, AttributeType="Scalar", Center="Node")
        _data_item(attribute, h5_name, dataset)
    elif len(shape) == 2 and shape[1] == dimension:
        attribute = ET.SubElement(grid, "Attribute", Name=name, AttributeType="Vector", Center="Node")
        _data_item(attribute, h5_name, dataset)
    else:
        # Voigt tensors (6 columns, xx yy zz yz xz xy) too: a Tensor6 attribute would
        # be read in XDMF's xx xy xz yy yz zz order and mislabel the components.
        # Rank-3 data (n, a, b) is described as (n, a*b): ParaView's XDMF2 reader
        # would otherwise take b for the number of components.
        attribute = ET.SubElement(grid, "Attribute", Name=name, AttributeType="Matrix", Center="Node")
        _data_item(attribute, h5_name, dataset, dims=(shape[0], int(np.prod(shape[1:]))))


def _number_type(dataset: h5py.Dataset) -> dict[str, str]:
    kind = "Int" if dataset.dtype.kind in "iu" else "Float"
    return {"NumberType": kind, "Precision": str(dataset.dtype.itemsize)}


def _data_item(
    parent: ET.Element, h5_name: str, dataset: h5py.Dataset, dims: tuple[int, ...] | None = None
) -> None:
    item = ET.SubElement(
        parent, "DataItem", Format="HDF",
        Dimensions=" ".join(str(d) for d in (dims or dataset.shape)), **_number_type(dataset),
    )
    item.text = f"{h5_name}:{dataset.name}"


def _write_atomically(path: Path, text: str) -> None:
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as handle:
            handle.write(text)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


# -- reading ---------------------------------------------------------------


def open_result(path: str | os.PathLike) -> h5py.File:
    """Open a result file for reading (no file lock: it may still be written)."""
    h5 = h5py.File(path, "r", locking=False)
    if h5.attrs.get("format") != FORMAT:
        h5.close()
        raise ValueError(f"{path} is not an MPM result file (format attribute {FORMAT!r} missing)")
    return h5


def _complete_frames(h5: h5py.File) -> list[str]:
    frames = h5.get("frames")
    if frames is None:
        return []
    return sorted(name for name in frames if "step" in frames[name].attrs)


def list_frames(path: str | os.PathLike) -> list[dict[str, Any]]:
    """Every complete frame: ``[{"index", "name", "time", "step", "particles", "fields"}]``.

    ``fields`` lists the frame's dataset names; no particle data is read.
    """
    with open_result(path) as h5:
        return [
            {
                "index": index,
                "name": name,
                "time": float(h5["frames"][name].attrs["time"]),
                "step": int(h5["frames"][name].attrs["step"]),
                "particles": int(h5["frames"][name]["position"].shape[0]),
                "fields": sorted(h5["frames"][name]),
            }
            for index, name in enumerate(_complete_frames(h5))
        ]


class FrameNotFound(SolverError, IndexError):
    """A frame the result file does not have (``count``: the frames it has, maybe 0)."""

    def __init__(self, path: str | os.PathLike, frame: int, count: int):
        self.path, self.frame, self.count = path, frame, count
        super().__init__(self.describe(path))

    def describe(self, file: object) -> str:
        """The message, naming the file as ``file`` (a server shows no path of its own)."""
        if not self.count:
            return f"{file} has no frames yet"
        return f"frame {self.frame} is out of range: {file} has {self.count} frames (0..{self.count - 1})"


# A preview (solver/preview.py) draws at most this many particles (every k-th of a larger frame, each marker k^(1/d)
# times larger): matplotlib takes about 600 bytes and 0.5 ms a point in 3D (benchmarks/memory.py),
# so a frame of millions would cost the run more memory than its simulation and an hour of drawing.
MAX_PREVIEW_POINTS = 250_000


def read_frame(path: str | os.PathLike, frame: int = -1, max_rows: int | None = None) -> dict[str, Any]:
    """One frame (``-1``: the last): ``{"index", "name", "time", "step", "every", "fields": {name: array}}``;
    `max_rows`: read every k-th particle only (``every`` = k), k the least that keeps to it.

    Raises :class:`FrameNotFound` (an ``IndexError``) for a frame out of range."""
    with open_result(path) as h5:
        names = _complete_frames(h5)
        if not -len(names) <= frame < len(names):
            raise FrameNotFound(path, frame, len(names))
        index = frame % len(names)
        group = h5["frames"][names[index]]
        rows = group["id"].shape[0] if "id" in group else 0
        every = max(1, -(-rows // max_rows)) if max_rows else 1
        return {
            "index": index,
            "name": names[index],
            "time": float(group.attrs["time"]),
            "step": int(group.attrs["step"]),
            "every": every,
            "fields": {key: group[key][()] if every == 1 else group[key][::every] for key in group},
        }


def read_series(path: str | os.PathLike) -> dict[str, np.ndarray]:
    """The time series written so far, ``{name: 1-D float64 array}``."""
    with open_result(path) as h5:
        series = h5.get("time_series")
        return {} if series is None else {key: series[key][()] for key in series}


def read_scene(path: str | os.PathLike) -> dict[str, Any]:
    """The scene stored in a result file, as a plain dict."""
    with open_result(path) as h5:
        return json.loads(h5.attrs["scene"])
