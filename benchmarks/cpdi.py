"""CPDI-R4's, CPDI-Q4's and CPDI-Tet4's cost per particle-step against linear hats and uGIMP on the same scene:
docs/benchmarks.md, section "F-bar and CPDI".

    python benchmarks/cpdi.py [--rounds 5] [--steps 40] [--only-2d | --only-3d]

Scenes: the E6 unit square (2D, h = 1/32, 2 x 2 particles per cell: 4096 particles)
and the E6 unit cube (3D, h = 1/8, 2 x 2 x 2 per cell: 4096 particles), ULMPM,
MUSL, FLIP, all with the general (stored-stencil) backend so that the shape
function is the only difference (the fused backend, which runs linear scenes by
default, is timed too, as what a user of `linear` gets). The methods are stepped
alternately, `rounds` rounds of `steps` steps each; the table gives the best time
per particle-step of each and its ratio to GIMP's, with the spread of the
per-round ratios (the machine is shared: the best round is the least disturbed).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from interleaved import round_times  # noqa: E402

from solver.manufactured import Options, cube_scene  # noqa: E402
from solver.scene import load_scene  # noqa: E402
from solver.stepper import ExplicitMPM  # noqa: E402

SCENES = {"2D square h=1/32": (2, 1 / 32), "3D cube h=1/8": (3, 1 / 8)}
METHODS = [("linear", False), ("linear", True), ("gimp", True), ("cpdi_r4", True), ("cpdi_q4", True),
           ("cpdi_tet4", True)]
DIMENSIONS = {"cpdi_q4": 2, "cpdi_tet4": 3}   # quadrilaterals, tetrahedra


def stepper(dim: int, h: float, shape: str, general: bool) -> tuple[ExplicitMPM, float]:
    scene = load_scene(cube_scene(dim, h, 0.05, Options(formulation="ulmpm", shape=shape)))
    sim = ExplicitMPM(scene, general=general)
    sim.advance(scene.time.dt)   # compile
    return sim, scene.time.dt


def compare(dim: int, h: float, rounds: int, steps: int) -> list[str]:
    sims = {(shape, general): stepper(dim, h, shape, general) for shape, general in METHODS
            if DIMENSIONS.get(shape, dim) == dim}
    times = round_times(sims, rounds, steps)
    best = {key: min(t) for key, t in times.items()}
    ratios = {key: [a / b for a, b in zip(t, times[("gimp", True)])] for key, t in times.items()}
    rows = []
    for (shape, general), (sim, _) in sims.items():
        key = (shape, general)
        backend = "general" if general else sim.phases.name
        rows.append(f"| {shape} ({backend}) | {best[key] * 1e9:.0f} | {best[key] / best[('gimp', True)]:.2f} "
                    f"| {min(ratios[key]):.2f}-{max(ratios[key]):.2f} |")
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--steps", type=int, default=40)
    parser.add_argument("--only-2d", action="store_true")
    parser.add_argument("--only-3d", action="store_true")
    args = parser.parse_args()
    for name, (dim, h) in SCENES.items():
        if (args.only_2d and dim != 2) or (args.only_3d and dim != 3):
            continue
        print(f"\n{name}, {args.rounds} rounds of {args.steps} steps\n")
        print("| shape function (backend) | ns per particle-step, best | / gimp | per-round ratios |")
        print("|---|---|---|---|")
        for row in compare(dim, h, args.rounds, args.steps):
            print(row, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
