"""CPDI-R4's, CPDI-Q4's and CPDI-Tet4's cost per particle-step against linear hats and uGIMP on the same scene:
docs/benchmarks.md, section "F-bar and CPDI".

    python benchmarks/cpdi.py [--rounds 5] [--steps 40] [--only-2d | --only-3d]

Scenes: the E6 unit square (2D, h = 1/32, 2 x 2 particles per cell: 4096 particles)
and the E6 unit cube (3D, h = 1/8, 2 x 2 x 2 per cell: 4096 particles), ULMPM,
MUSL, FLIP, all with the general (stored-stencil) backend so that the shape
function is the only difference (the fused backend, which runs linear scenes by
default, is timed too, as what a user of `linear` gets). CPDI runs on its compact
stencil (3 nodes per axis while every domain spans at most two cells per axis, as
here) and, as "wide", on the 4-node one it widens to (every CPDI run before the
compact stencil: the same results bit for bit). The methods are stepped
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
from solver.scene_checks import load_scene  # noqa: E402
from solver.stepper import ExplicitMPM  # noqa: E402

SCENES = {"2D square h=1/32": (2, 1 / 32), "3D cube h=1/8": (3, 1 / 8)}
GENERAL, WIDE = "general", "general, wide stencil"
METHODS = [("linear", "fused"), ("linear", GENERAL), ("gimp", GENERAL), ("cpdi_r4", GENERAL), ("cpdi_r4", WIDE),
           ("cpdi_q4", GENERAL), ("cpdi_q4", WIDE), ("cpdi_tet4", GENERAL), ("cpdi_tet4", WIDE)]
DIMENSIONS = {"cpdi_q4": 2, "cpdi_tet4": 3}   # quadrilaterals, tetrahedra


def stepper(dim: int, h: float, shape: str, backend: str) -> tuple[ExplicitMPM, float]:
    scene = load_scene(cube_scene(dim, h, 0.05, Options(formulation="ulmpm", shape=shape)))
    sim = ExplicitMPM(scene, general=backend != "fused")
    if backend == WIDE:
        sim.phases._widen_stencil()
        sim.phases.weights()
    sim.advance(scene.time.dt)   # compile
    return sim, scene.time.dt


def compare(dim: int, h: float, rounds: int, steps: int) -> list[str]:
    sims = {(shape, backend): stepper(dim, h, shape, backend) for shape, backend in METHODS
            if DIMENSIONS.get(shape, dim) == dim}
    times = round_times(sims, rounds, steps)
    best = {key: min(t) for key, t in times.items()}
    gimp = ("gimp", GENERAL)
    ratios = {key: [a / b for a, b in zip(t, times[gimp])] for key, t in times.items()}
    rows = []
    for (shape, backend), (sim, _) in sims.items():
        key = (shape, backend)
        assert backend != "fused" or sim.fused
        wide = (shape, WIDE)
        to_wide = ""
        if backend == GENERAL and wide in sims:   # the compact stencil against the wide one, round by round
            per_round = [a / b for a, b in zip(times[key], times[wide])]
            to_wide = f"{best[key] / best[wide]:.2f} ({min(per_round):.2f}-{max(per_round):.2f})"
        rows.append(f"| {shape} ({backend}) | {best[key] * 1e9:.0f} | {best[key] / best[gimp]:.2f} "
                    f"| {min(ratios[key]):.2f}-{max(ratios[key]):.2f} | {to_wide} |")
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
        print("| shape function (backend) | ns per particle-step, best | / gimp | per-round ratios "
              "| / wide stencil (per round) |")
        print("|---|---|---|---|---|")
        for row in compare(dim, h, args.rounds, args.steps):
            print(row, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
