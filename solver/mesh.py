"""Closed triangle meshes: reading STL (ASCII or binary) and OBJ, the checks a body's
mesh must pass, and the inside test of the `mesh` geometry.

The readers are small numpy readers rather than a mesh library: both formats are a
list of triangles (STL) or of vertices and faces (OBJ), a library would add repairs
and merges by tolerance that would silently change a user's part, and these readers
open nothing but the bytes they are given (an OBJ's `mtllib` is never followed), which
is what the service needs for meshes sent as data.

Vertices are welded by their exact coordinates (STL repeats each vertex in every
triangle; a CAD exporter writes the same bits each time). A mesh is closed when every
edge is shared by an even number of triangles; orientation does not matter, because
the inside test counts crossings (the even-odd rule), as for polygons.
"""
from __future__ import annotations

import base64
import binascii
import copy
import math
import os
import re
from dataclasses import dataclass
from functools import cached_property

import numpy as np

FORMATS = ("stl", "obj")
DEFAULT_MAX_MESH_BYTES = 64 * 2**20   # a 1.3-million-triangle binary STL
BINARY_STL_HEADER = 84                # 80 bytes of text, a uint32 count
BINARY_STL_RECORD = np.dtype([("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])


class GeometryFileError(ValueError):
    """A geometry's file or data that cannot be used (too large, unreadable, not base64)."""


class MeshError(GeometryFileError):
    """A mesh that cannot be a body: the message says what is wrong with it."""


def max_mesh_bytes() -> int:
    """The largest mesh accepted, in bytes of its file: MPM_MAX_MESH_BYTES, else the default."""
    text = os.environ.get("MPM_MAX_MESH_BYTES", "").strip()
    return int(text) if text.isdigit() and int(text) > 0 else DEFAULT_MAX_MESH_BYTES


def format_of(path: str) -> str | None:
    """The format a file name's suffix says, None when it says none of FORMATS."""
    suffix = os.path.splitext(path)[1].lower().lstrip(".")
    return suffix if suffix in FORMATS else None


def decode_data(data: str, limit: int) -> bytes:
    """The bytes of a base64 string, refused before decoding when they would exceed `limit`."""
    if len(data) // 4 * 3 > limit + 3:
        raise GeometryFileError(f"the mesh data ({len(data) // 4 * 3} bytes decoded) is larger than the limit of "
                        f"{limit} bytes (MPM_MAX_MESH_BYTES)")
    try:
        return base64.b64decode(data, validate=True)
    except (binascii.Error, ValueError) as exc:
        raise GeometryFileError(f"does not decode as base64: {exc}") from None


def read_file(path: str, limit: int, kind: str = "mesh") -> bytes:
    """The bytes of a geometry's file (`kind`: mesh, points), refused before reading when
    larger than `limit`."""
    try:
        size = os.path.getsize(path)
        if size > limit:
            raise GeometryFileError(f"the {kind} file {path!r} ({size} bytes) is larger than the limit of {limit} "
                                    "bytes (MPM_MAX_MESH_BYTES)")
        with open(path, "rb") as handle:
            return handle.read(limit + 1)
    except OSError as exc:
        raise GeometryFileError(f"cannot read the {kind} file {path!r}: {exc.strerror or exc}") from None


def read_triangles(raw: bytes, fmt: str) -> np.ndarray:
    """(T, 3, 3) float64 triangle corners of an STL or OBJ file's bytes."""
    triangles = _read_stl(raw) if fmt == "stl" else _read_obj(_text(raw))
    if len(triangles) == 0:
        raise MeshError(f"the {fmt.upper()} mesh has no triangles")
    if not np.all(np.isfinite(triangles)):
        raise MeshError("the mesh has coordinates that are not finite numbers")
    return triangles


def _text(raw: bytes) -> str:
    try:
        return raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise MeshError(f"is not a text file (byte {exc.start} is not UTF-8)") from None


def _read_stl(raw: bytes) -> np.ndarray:
    """Binary when the size is exactly the header plus the records its count announces
    (some binary files start with "solid" too), else ASCII."""
    announced = None
    if len(raw) >= BINARY_STL_HEADER:
        announced = int(np.frombuffer(raw, dtype="<u4", count=1, offset=80)[0])
        if len(raw) == BINARY_STL_HEADER + announced * BINARY_STL_RECORD.itemsize:
            records = np.frombuffer(raw, dtype=BINARY_STL_RECORD, count=announced, offset=BINARY_STL_HEADER)
            return records["vertices"].astype(np.float64)
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        text = ""
    if not text.lstrip().lower().startswith("solid"):
        binary = (f"its {len(raw)} bytes do not match the {announced} triangles its header announces "
                  f"({BINARY_STL_HEADER + (announced or 0) * BINARY_STL_RECORD.itemsize} bytes)"
                  if announced is not None else f"{len(raw)} bytes, shorter than a binary header")
        raise MeshError(f"is neither a binary STL ({binary}) nor an ASCII STL (text starting with 'solid')")
    corners = re.findall(r"^\s*vertex\s+(\S+)\s+(\S+)\s+(\S+)", text, flags=re.MULTILINE | re.IGNORECASE)
    facets = len(re.findall(r"^\s*facet\b", text, flags=re.MULTILINE | re.IGNORECASE))
    if len(corners) != 3 * facets:
        raise MeshError(f"the ASCII STL has {facets} facets but {len(corners)} vertices (3 per facet expected)")
    return _numbers(corners, "vertex").reshape(-1, 3, 3)


def _numbers(rows: list, what: str) -> np.ndarray:
    try:
        return np.array(rows, dtype=np.float64)
    except ValueError as exc:
        raise MeshError(f"a {what} line has a coordinate that is not a number: {exc}") from None


def _read_obj(text: str) -> np.ndarray:
    """`v x y z` vertices and `f i j k ...` faces (1-based, negative: from the end,
    `i/t/n` forms allowed); polygons are split into fans of triangles."""
    vertices, faces = [], []
    for number, line in enumerate(text.splitlines(), start=1):
        words = line.split()
        if not words:
            continue
        if words[0] == "v":
            vertices.append(words[1:4])
        elif words[0] == "f":
            try:
                corners = [int(word.split("/")[0]) for word in words[1:]]
            except ValueError:
                raise MeshError(f"line {number}: a face index is not a whole number: {line.strip()!r}") from None
            if len(corners) < 3:
                raise MeshError(f"line {number}: a face needs at least 3 vertices: {line.strip()!r}")
            faces.append((number, len(vertices), corners))
    points = _numbers(vertices, "v") if vertices else np.empty((0, 3))
    if points.ndim != 2 or points.shape[1] != 3:
        raise MeshError("every 'v' line needs 3 coordinates")
    triangles = []
    for number, known, corners in faces:
        index = [c - 1 if c > 0 else known + c for c in corners]   # negative: relative to the vertices so far
        if any(i < 0 or i >= len(points) or c == 0 for i, c in zip(index, corners)):
            raise MeshError(f"line {number}: a face refers to a vertex that does not exist ({len(points)} vertices)")
        triangles += [(index[0], index[k], index[k + 1]) for k in range(1, len(index) - 1)]
    return points[np.array(triangles, dtype=np.int64).reshape(-1, 3)]


def open_edges(triangles: np.ndarray) -> int:
    """Edges (of the mesh welded by exact coordinates) shared by an odd number of
    triangles; 0 for a closed mesh. Triangles with two equal corners are left out."""
    corner = weld(triangles.reshape(-1, 3)).reshape(-1, 3)
    proper = (corner[:, 0] != corner[:, 1]) & (corner[:, 1] != corner[:, 2]) & (corner[:, 2] != corner[:, 0])
    corner = corner[proper]
    edges = np.sort(np.concatenate([corner[:, [0, 1]], corner[:, [1, 2]], corner[:, [2, 0]]]), axis=1)
    _, counts = np.unique(edges[:, 0] * (int(corner.max(initial=0)) + 1) + edges[:, 1], return_counts=True)
    return int(np.count_nonzero(counts % 2))


def weld(points: np.ndarray) -> np.ndarray:
    """For each point, the index of its distinct value (equal bits, -0.0 as 0.0): a sort of
    the coordinates' bits, much faster than np.unique(axis=0) (a 327,680-triangle mesh: 0.3 s)."""
    bits = np.ascontiguousarray(points + 0.0).view(np.int64)
    order = np.lexsort(bits.T[::-1])
    ordered = bits[order]
    new = np.ones(len(points), dtype=bool)
    new[1:] = np.any(ordered[1:] != ordered[:-1], axis=1)
    index = np.empty(len(points), dtype=np.int64)
    index[order] = np.cumsum(new) - 1
    return index


def load(raw: bytes, fmt: str, scale: float, translate) -> "Mesh":
    """The Mesh of a file's bytes, placed (scaled, then translated); MeshError when it is
    empty or not closed."""
    triangles = read_triangles(raw, fmt)
    count = open_edges(triangles)
    if count:
        raise MeshError(f"mesh is not closed: {count} open edge{'s' if count != 1 else ''} "
                        "(edges of only one triangle); a body needs a closed (watertight) surface")
    return Mesh(triangles * scale + np.asarray(translate, dtype=np.float64))


@dataclass(frozen=True, eq=False)
class Mesh:
    """A closed triangle mesh as a geometry: `contains` by the even-odd rule along +z.

    Each point's vertical ray is tested against the triangles whose xy bounding box
    covers the point's bin of a uniform xy grid; the test runs in a compiled kernel
    (solver/mesh_kernels.py) over all the points at once."""

    triangles: np.ndarray   # (T, 3, 3)

    def bounding_box(self):
        corners = self.triangles.reshape(-1, 3)
        return corners.min(axis=0), corners.max(axis=0)

    @cached_property
    def _bins(self):
        return xy_bins(self.triangles)

    def contains(self, points: np.ndarray) -> np.ndarray:
        from solver.mesh_kernels import inside_mesh

        triangles, lower, inverse, shape, start, items = self._bins
        out = np.zeros(len(points), dtype=np.bool_)
        if len(points):
            inside_mesh(np.ascontiguousarray(points, dtype=np.float64), triangles, lower, inverse,
                        shape[0], shape[1], start, items, out)
        return out


def xy_bins(triangles: np.ndarray, entries_per_triangle: int = 8):
    """The triangles that are not vertical (their xy projection has an area), and a uniform
    xy grid of bins listing, for each bin, the triangles whose xy box overlaps it: CSR
    arrays (start, items). About one bin per triangle, made coarser while the lists would
    hold more than `entries_per_triangle` entries per triangle (large faces cover many bins)."""
    xy = triangles[:, :, :2]
    area = ((xy[:, 1, 0] - xy[:, 0, 0]) * (xy[:, 2, 1] - xy[:, 0, 1])
            - (xy[:, 1, 1] - xy[:, 0, 1]) * (xy[:, 2, 0] - xy[:, 0, 0]))
    kept = np.ascontiguousarray(triangles[area != 0.0])
    lower, upper = triangles[:, :, :2].reshape(-1, 2).min(axis=0), triangles[:, :, :2].reshape(-1, 2).max(axis=0)
    extent = np.maximum(upper - lower, 1e-300)
    low, high = kept[:, :, :2].min(axis=1), kept[:, :, :2].max(axis=1)
    target = max(1.0, float(len(kept)))
    while True:
        per_length = math.sqrt(target / (extent[0] * extent[1])) if extent.min() > 0 else target / extent.max()
        shape = np.maximum(1, np.minimum(4096, np.ceil(extent * per_length))).astype(np.int64)
        inverse = shape / extent
        first = np.clip(np.floor((low - lower) * inverse), 0, shape - 1).astype(np.int64)
        last = np.clip(np.floor((high - lower) * inverse), 0, shape - 1).astype(np.int64)
        spans = last - first + 1
        counts = spans[:, 0] * spans[:, 1]
        if counts.sum() <= entries_per_triangle * len(kept) + shape.prod() or target <= 1:
            break
        target /= 4
    owner = np.repeat(np.arange(len(kept)), counts)
    offset = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
    bx = first[owner, 0] + offset % spans[owner, 0]
    by = first[owner, 1] + offset // spans[owner, 0]
    bin_of = bx * shape[1] + by
    order = np.argsort(bin_of, kind="stable")
    start = np.zeros(shape.prod() + 1, dtype=np.int64)
    np.cumsum(np.bincount(bin_of, minlength=shape.prod()), out=start[1:])
    return kept, lower, inverse, shape, start, np.ascontiguousarray(owner[order])


def inline_files(document, folder):
    """A copy of a scene document with every mesh geometry's "file" (relative to `folder`)
    replaced by the file's bytes as "data" (base64) and its "format": a document that
    runs anywhere, as the service needs (the built-in examples). The SDK does the same
    on the client's side (mpm_client.scenes, which does not import the solver)."""
    document = copy.deepcopy(document)
    for geometry in _file_meshes(document):
        path = os.path.join(folder, geometry.pop("file"))
        geometry["format"] = geometry.get("format") or format_of(path)
        geometry["data"] = base64.b64encode(read_file(path, max_mesh_bytes())).decode("ascii")
    return document


def _file_meshes(node):
    """Every dict under `node` that is a mesh geometry naming a file."""
    children = node.values() if isinstance(node, dict) else node if isinstance(node, list) else ()
    for child in children:
        yield from _file_meshes(child)
    if isinstance(node, dict) and node.get("type") == "mesh" and isinstance(node.get("file"), str):
        yield node
