"""The `mesh` geometry's inside test at a million points, beside the sphere's -> docs/benchmarks.md.

    python benchmarks/mesh_inside.py [--points N] [--repeat R]

Icospheres of 1,280 to 327,680 triangles (unit radius) against N points in their
bounding box, on a lattice visited in C order as seeding visits its candidates (or in
random order with --random: the worst case for the memory caches), timed side by side with the analytic `sphere` geometry of the
same radius on the same points (the cheapest inside test there is: one line of
numpy), and with the time to read and check the mesh (binary STL bytes -> welded,
closed-checked Mesh). Prints the best of R runs and the spread (max/min), and the
share of points that the two tests classify differently (those lie between the
polyhedron and the sphere it is inscribed in: the polyhedron's volume deficit).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "verification"))

from mesh_shapes import binary_stl, icosphere  # noqa: E402

from solver import mesh  # noqa: E402
from solver.geometry import Sphere  # noqa: E402


def timed(function, repeat: int) -> tuple[float, float, object]:
    times, result = [], None
    for _ in range(repeat):
        start = time.perf_counter()
        result = function()
        times.append(time.perf_counter() - start)
    return min(times), max(times) / min(times), result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=1_000_000)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--random", action="store_true", help="random points instead of a lattice")
    args = parser.parse_args()
    if args.random:
        points = np.random.default_rng(0).uniform(-1.0, 1.0, (args.points, 3))
    else:
        side = round(args.points ** (1 / 3))
        axis = -1 + (np.arange(side) + 0.5) * 2 / side
        points = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)
        args.points = len(points)
    sphere = Sphere(np.zeros(3), 1.0)
    mesh.Mesh(icosphere(1)).contains(points[:10])   # compile (or load the cache) outside the timings
    print(f"{args.points:,} points, best of {args.repeat} (spread max/min)")
    print(f"{'triangles':>10} {'read+check s':>13} {'mesh s':>8} {'sphere s':>9} {'ratio':>6} {'differ %':>9}")
    for subdivisions in (3, 5, 7):
        raw = binary_stl(icosphere(subdivisions))
        read, read_spread, shape = timed(lambda: mesh.load(raw, "stl", 1.0, [0, 0, 0]), 1)
        inside, spread, got = timed(lambda: shape.contains(points), args.repeat)
        exact, exact_spread, expected = timed(lambda: sphere.contains(points), args.repeat)
        differ = 100 * np.count_nonzero(got != expected) / args.points
        print(f"{len(shape.triangles):>10,} {read:>13.3f} {inside:>8.3f} {exact:>9.3f} {inside / exact:>6.1f} "
              f"{differ:>9.3f}   spread mesh {spread:.2f} sphere {exact_spread:.2f}")


if __name__ == "__main__":
    main()
