"""Steps/s of the general (stored-stencil) kernels at 1 and 2 threads -> docs/benchmarks.md.

    nice -n 19 python benchmarks/general_threads.py [--steps 20] [--repeats 5]

Two scenes the fused kernels do not take: a 2D GIMP MUSL FLIP scene (two elastic
disks colliding, ~40k particles) and a 3D TLMPM block (linear, MUSL, ~50k
particles). Both thread counts run in this one process, alternating, so that the
ratio sees the same machine load; the best of the repeats is reported.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numba

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from solver.scene_checks import load_scene  # noqa: E402
from solver.stepper import ExplicitMPM  # noqa: E402

ELASTIC = {"model": "neo_hookean", "density": 1000.0, "youngs_modulus": 1e6, "poisson_ratio": 0.3}

GIMP_2D = {
    "name": "gimp-2d", "dimension": 2,
    "method": {"scheme": "musl", "transfer": "flip", "flip_ratio": 0.99, "shape_function": "gimp"},
    "grid": {"lower": [0.0, 0.0], "upper": [1.0, 0.5], "cell_size": 0.0025},
    "materials": {"m": ELASTIC},
    "bodies": [
        {"name": "left", "material": "m", "particles_per_cell": 2, "initial_velocity": [0.5, 0.0],
         "geometry": {"type": "sphere", "center": [0.38, 0.25], "radius": 0.1}},
        {"name": "right", "material": "m", "particles_per_cell": 2, "initial_velocity": [-0.5, 0.0],
         "geometry": {"type": "sphere", "center": [0.62, 0.25], "radius": 0.1}},
    ],
    "gravity": [0.0, -9.81],
    "time": {"end": 1.0, "dt": 1e-5},
}

TLMPM_3D = {
    "name": "tlmpm-3d", "dimension": 3,
    "method": {"formulation": "tlmpm", "scheme": "musl", "transfer": "flip", "flip_ratio": 0.99},
    "grid": {"lower": [0.0, 0.0, 0.0], "upper": [0.6, 0.3, 0.3], "cell_size": 0.0125},
    "materials": {"m": ELASTIC},
    "bodies": [{"name": "block", "material": "m", "particles_per_cell": 2,
                "initial_velocity": ["0.1 * sin(3 * x)", 0.05, 0.0],
                "geometry": {"type": "box", "lower": [0.05, 0.05, 0.05], "upper": [0.55, 0.25, 0.25]}}],
    "gravity": [0.0, 0.0, -9.81],
    "time": {"end": 1.0, "dt": 1e-6},
}


def make(scene: dict, threads: int):
    scene = {**scene, "parallel": {"processes": 1, "threads": threads}}
    loaded = load_scene(scene)
    return ExplicitMPM(loaded)


def measure(scene: dict, steps: int, repeats: int, counts=(1, 2)) -> dict:
    sims = {t: make(scene, t) for t in counts}
    dt = scene["time"]["dt"]
    best = {t: float("inf") for t in sims}
    for sim in sims.values():   # compile and warm up
        numba.set_num_threads(sim.threads)
        sim.advance(dt)
    for _ in range(repeats):
        for t, sim in sims.items():
            numba.set_num_threads(sim.threads)
            start = time.perf_counter()
            for _ in range(steps):
                sim.advance(dt)
            best[t] = min(best[t], (time.perf_counter() - start) / steps)
    return {"particles": sims[counts[0]].particles.count, **{t: 1.0 / s for t, s in best.items()}}


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--steps", type=int, default=20)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    print("| scene | particles | steps/s, 1 thread | steps/s, 2 threads | speedup |")
    print("|---|---:|---:|---:|---:|")
    for name, scene in (("2D GIMP MUSL FLIP", GIMP_2D), ("3D TLMPM linear MUSL FLIP", TLMPM_3D)):
        r = measure(scene, args.steps, args.repeats)
        print(f"| {name} | {r['particles']} | {r[1]:.1f} | {r[2]:.1f} | {r[2] / r[1]:.2f} |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
