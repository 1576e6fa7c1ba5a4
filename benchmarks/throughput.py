"""Solver throughput in particle-steps per second, against a hand-fused reference.

    python benchmarks/throughput.py            # the table of docs/benchmarks.md
    python benchmarks/throughput.py --quick    # smaller problems, fewer steps

Each case is an elastic block (linear shape functions, MUSL, FLIP, one thread).
The reference is the same 2D step written as one fused numba function with
every loop unrolled by hand (benchmarks/reference_mpm2d.py): the ceiling for
this algorithm on this machine. Both run alternately in the same process, so
the ratio holds on a busy, shared machine where absolute numbers do not.
It also measures the start-up of `python -m solver run` with a warm compile cache.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from reference_mpm2d import ReferenceMPM2D  # noqa: E402
from solver.scene import load_scene  # noqa: E402
from solver.stepper import ExplicitMPM  # noqa: E402

DT = 1e-6


def block_scene(dim: int, cells_per_axis: int) -> dict:
    """A block filling 80 % of the unit grid, 2 particles per cell per axis, moving and straining."""
    h = 1.0 / cells_per_axis
    return {
        "version": 1, "name": f"block-{dim}d", "dimension": dim,
        "method": {"scheme": "musl", "shape_function": "linear", "transfer": "flip", "flip_ratio": 0.99},
        "grid": {"lower": [0.0] * dim, "upper": [1.0] * dim, "cell_size": h},
        "materials": {"m": {"model": "linear_elastic", "density": 1000.0, "youngs_modulus": 1e6, "poisson_ratio": 0.3}},
        "bodies": [{"name": "block", "material": "m", "particles_per_cell": 2,
                    "geometry": {"type": "box", "lower": [0.1] * dim, "upper": [0.9] * dim},
                    "initial_velocity": ["0.1 * sin(3 * x)"] + ["0.05"] * (dim - 1)}],
        "time": {"end": 1.0, "dt": DT},
        "output": {"frames": 2, "fields": ["position"]},
    }


def rate(stepper, n_particles: int, steps: int) -> float:
    start = time.perf_counter()
    for _ in range(steps):
        stepper.advance(DT)
    return n_particles * steps / (time.perf_counter() - start)


def measure(dim: int, cells: int, steps: int, repeats: int) -> dict:
    sim = ExplicitMPM(load_scene(block_scene(dim, cells)))
    n = sim.particles.count
    sim.advance(DT)                       # compile (or load from cache)
    ours = []
    ref_rates = []
    reference = ReferenceMPM2D.from_simulation(sim) if dim == 2 else None
    if reference is not None:
        reference.advance(DT)
    for _ in range(repeats):             # alternate, keep the best of each: the least disturbed run
        ours.append(rate(sim, n, steps))
        if reference is not None:
            ref_rates.append(rate(reference, n, steps))
    row = {"dimension": dim, "particles": n, "grid_nodes": sim.grid.n_nodes, "steps": steps,
           "solver": max(ours)}
    if ref_rates:
        row["reference"] = max(ref_rates)
        row["ratio"] = row["solver"] / row["reference"]
    return row


def startup_seconds() -> float:
    """Wall time of `python -m solver run` on a tiny scene up to the end of its first step, warm cache."""
    scene = block_scene(2, 8)
    scene["time"] = {"end": DT, "dt": DT}
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "tiny.json"
        path.write_text(json.dumps(scene))
        code = ("import time, sys; t0 = time.perf_counter();"
                "from solver.scene import load_scene; from solver.stepper import ExplicitMPM;"
                "sim = ExplicitMPM(load_scene(sys.argv[1])); sim.advance(1e-6);"
                "print(time.perf_counter() - t0)")
        subprocess.run([sys.executable, "-c", code, str(path)], check=True, capture_output=True)   # warm the cache
        start = time.perf_counter()
        subprocess.run([sys.executable, "-c", code, str(path)], check=True, capture_output=True)
        return time.perf_counter() - start


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="small problems, for a smoke run")
    parser.add_argument("--json", type=Path, help="also write the rows as JSON")
    args = parser.parse_args()
    if args.quick:
        cases = [(2, 56, 20), (3, 14, 10)]
        repeats = 2
    else:
        # ~32k and ~130k particles in 2D (cells^2 * 0.64 * 4), ~130k in 3D (cells^3 * 0.512 * 8)
        cases = [(2, 112, 100), (2, 225, 40), (3, 32, 20)]
        repeats = 3
    rows = [measure(dim, cells, steps, repeats) for dim, cells, steps in cases]
    print(f"{'case':<10}{'particles':>11}{'nodes':>10}{'solver Mp-steps/s':>20}{'reference':>12}{'ratio':>8}")
    for r in rows:
        ref = f"{r['reference'] / 1e6:12.2f}" if "reference" in r else f"{'-':>12}"
        ratio = f"{r['ratio']:8.2f}" if "ratio" in r else f"{'-':>8}"
        print(f"{str(r['dimension']) + 'D block':<10}{r['particles']:>11,}{r['grid_nodes']:>10,}"
              f"{r['solver'] / 1e6:20.2f}{ref}{ratio}")
    start = startup_seconds()
    print(f"start-up to the end of the first step, warm cache: {start:.2f} s")
    if args.json:
        args.json.write_text(json.dumps({"rows": rows, "startup_seconds": start}, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
