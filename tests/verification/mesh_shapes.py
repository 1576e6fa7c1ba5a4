"""Closed triangle meshes for the tests: an icosphere and a cube, as (T, 3, 3) corner
arrays, and writers of the three file formats the `mesh` geometry reads."""
from __future__ import annotations

import numpy as np

_ICOSAHEDRON_FACES = np.array([
    [0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2], [10, 7, 6],
    [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5], [2, 4, 11], [6, 2, 10],
    [8, 6, 7], [9, 8, 1]])


def icosphere(subdivisions: int, radius: float = 1.0, center=(0.0, 0.0, 0.0)) -> np.ndarray:
    """The icosahedron with each triangle split in 4 `subdivisions` times, its vertices
    pushed onto the sphere: 20 * 4**subdivisions outward-facing triangles. Midpoints are
    computed from the same two corners in the same order on both sides of an edge, so
    shared vertices have the same bits (the mesh welds and closes)."""
    t = (1 + 5**0.5) / 2
    v = np.array([[-1, t, 0], [1, t, 0], [-1, -t, 0], [1, -t, 0], [0, -1, t], [0, 1, t], [0, -1, -t], [0, 1, -t],
                  [t, 0, -1], [t, 0, 1], [-t, 0, -1], [-t, 0, 1]], dtype=np.float64)
    v /= np.linalg.norm(v, axis=1)[:, None]
    tri = v[_ICOSAHEDRON_FACES]
    for _ in range(subdivisions):
        a, b, c = tri[:, 0], tri[:, 1], tri[:, 2]
        ab, bc, ca = _midpoint(a, b), _midpoint(b, c), _midpoint(c, a)
        tri = np.concatenate([np.stack(corners, axis=1) for corners in
                              ((a, ab, ca), (b, bc, ab), (c, ca, bc), (ab, bc, ca))])
    return tri * radius + np.asarray(center, dtype=np.float64)


def _midpoint(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """On the unit sphere; symmetric in p and q bit for bit (sorted before adding)."""
    first = np.where(_less(p, q)[:, None], p, q)
    second = np.where(_less(p, q)[:, None], q, p)
    m = first + second
    return m / np.sqrt((m * m).sum(axis=1))[:, None]


def _less(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Row-wise lexicographic p < q."""
    out = np.zeros(len(p), dtype=bool)
    decided = np.zeros(len(p), dtype=bool)
    for a in range(3):
        out |= ~decided & (p[:, a] < q[:, a])
        decided |= p[:, a] != q[:, a]
    return out


def polyhedron_volume(triangles: np.ndarray) -> float:
    """Exact (divergence theorem) for a closed, consistently oriented mesh."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    return abs(float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum()) / 6)


def cube(lower=(0.0, 0.0, 0.0), upper=(1.0, 1.0, 1.0)) -> np.ndarray:
    lo, up = np.asarray(lower, float), np.asarray(upper, float)
    corners = np.array([[i, j, k] for k in (0, 1) for j in (0, 1) for i in (0, 1)], dtype=float)
    corners = lo + corners * (up - lo)
    faces = [[0, 2, 3], [0, 3, 1], [4, 5, 7], [4, 7, 6], [0, 1, 5], [0, 5, 4],
             [1, 3, 7], [1, 7, 5], [3, 2, 6], [3, 6, 7], [2, 0, 4], [2, 4, 6]]
    return corners[np.array(faces)]


def binary_stl(triangles: np.ndarray, header: bytes = b"binary") -> bytes:
    records = np.zeros(len(triangles), dtype=[("normal", "<f4", 3), ("vertices", "<f4", (3, 3)), ("attribute", "<u2")])
    records["vertices"] = triangles
    return header.ljust(80, b" ") + np.uint32(len(triangles)).tobytes() + records.tobytes()


def ascii_stl(triangles: np.ndarray) -> bytes:
    lines = ["solid test"]
    for t in triangles:
        lines += ["facet normal 0 0 0", " outer loop"] + [f"  vertex {x!r} {y!r} {z!r}" for x, y, z in t.tolist()]
        lines += [" endloop", "endfacet"]
    return ("\n".join(lines + ["endsolid test"]) + "\n").encode()


def obj(triangles: np.ndarray) -> bytes:
    """Vertices welded, faces 1-based; every second face written with negative indices."""
    points, index = np.unique(triangles.reshape(-1, 3), axis=0, return_inverse=True)
    index = index.reshape(-1, 3)
    lines = [f"v {x!r} {y!r} {z!r}" for x, y, z in points.tolist()]
    for k, face in enumerate(index.tolist()):
        lines.append("f " + " ".join(str(i + 1) if k % 2 else f"{i - len(points)}/1/1" for i in face))
    return ("\n".join(lines) + "\n").encode()
