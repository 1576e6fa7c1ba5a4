"""A choice of the fused plan (solver/step/fused.py CHOICES) on and off, side by side in one
process: the step with the stress formed in P2G (`forms_stress`) or updated in G2P
(`updates_stress`) against the same scene with the separate stress pass, or with the force
folded into the momentum (`fold`) against f_I formed apart, taking turns (so a shared machine's
load hits both alike).

    python benchmarks/fused_switch_ab.py                                  # updates_stress, FLIP block
    python benchmarks/fused_switch_ab.py --switch g2p_kinematics --dims 2   # MUSL's vectorised pass
    python benchmarks/fused_switch_ab.py --switch forms_stress --block mls --dims 2 --threads 1 2
    python benchmarks/fused_switch_ab.py --switch lanes --block mls --dims 3   # 3D MLS in four lanes

The blocks are benchmarks/throughput.py's: "flip" its part-2 block (linear elastic, linear hats,
MUSL, FLIP 0.99), "apic" / "mls" its side-by-side block (neo-Hookean, quadratic B-splines, USL),
"mpm88" the fluid (2D only). Two copies of the scene are built, the switch turned off on the
second; after a warm-up, --rounds rounds of --steps steps run on each in turn. The table gives
ns per particle-step with the switch on and off (median and best of the rounds) and off / on
(above 1: the switch makes the step faster). Both copies end in the same state to round-off
(tests/unit/test_fused.py checks it: `fold` joins the force's sum to the momentum's, and
with FMA contraction, the default, a fused kernel may fuse a multiply and an add that a
material's own pass does not; the other switches keep the bits with MPM_FMA=0, and `lanes`
with contraction too); this script checks the positions to 1e-12. A switch that is off for a
block (updates_stress on the 2D FLIP block, whose KINEMATICS pass is the vectorised
`g2p_kinematics`, without the update) gets a row that says so.
"""
from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numba
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "benchmarks")]

from throughput import DT, MLS_DT, MPM88_DT, block_scene, mls_block_scene, mpm88_scene  # noqa: E402
from solver.scene_checks import load_scene  # noqa: E402
from solver.stepper import ExplicitMPM  # noqa: E402
from solver.step.fused import CHOICES  # noqa: E402


def scene_of(block: str, dim: int, threads: int) -> tuple[dict, float]:
    if block == "mpm88":
        return mpm88_scene(threads), MPM88_DT
    cells = 225 if dim == 2 else 32
    if block == "flip":
        scene = block_scene(dim, cells)
        scene["parallel"] = {"threads": threads}
        return scene, DT
    return mls_block_scene(dim, cells, threads, block), MLS_DT


def compare(switch: str, block: str, dim: int, threads: int, rounds: int, steps: int) -> dict | None:
    numba.set_num_threads(threads)
    scene, dt = scene_of(block, dim, threads)
    loaded = load_scene(scene)
    on, off = ExplicitMPM(loaded), ExplicitMPM(loaded)
    if not on.phases.plan.makes(switch):
        return None
    off.phases.replan(without=(switch,))
    times = {"on": [], "off": []}
    for sim in (on, off):
        for _ in range(3):
            sim.advance(dt)
    for _ in range(rounds):
        for name, sim in (("on", on), ("off", off)):
            start = time.perf_counter()
            for _ in range(steps):
                sim.advance(dt)
            times[name].append((time.perf_counter() - start) / steps / sim.particles.count * 1e9)
    x_on, x_off = on.particles.x, off.particles.x
    moved = np.abs(x_on - x_off).max() / np.abs(x_off).max()
    if moved > 1e-12:
        raise SystemExit(f"the two copies' positions differ by {moved:.1e}: more than round-off")
    med, best = ({k: f(v) for k, v in times.items()} for f in (statistics.median, min))
    return {"block": block, "dim": dim, "threads": threads, "median": med, "best": best}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--switch", default="updates_stress",
                        choices=CHOICES)
    parser.add_argument("--block", choices=("flip", "apic", "mls", "mpm88"), default="flip")
    parser.add_argument("--dims", nargs="+", type=int, default=[2, 3])
    parser.add_argument("--threads", nargs="+", type=int, default=[1, 2])
    parser.add_argument("--rounds", type=int, default=25)
    parser.add_argument("--steps", type=int, default=5)
    args = parser.parse_args()
    print(f"| block | dim | threads | {args.switch} on (ns, median / best) | off | off / on, median | best |")
    print("|---|---|---|---|---|---|---|")
    for dim in ([2] if args.block == "mpm88" else args.dims):
        for threads in args.threads:
            r = compare(args.switch, args.block, dim, threads, args.rounds, args.steps)
            if r is None:
                print(f"| {args.block} | {dim} | {threads} | {args.switch} is off for this block | | | |", flush=True)
                continue
            med, best = r["median"], r["best"]
            print(f"| {args.block} | {dim} | {threads} | {med['on']:.1f} / {best['on']:.1f} | "
                  f"{med['off']:.1f} / {best['off']:.1f} | {med['off'] / med['on']:.3f} | "
                  f"{best['off'] / best['on']:.3f} |", flush=True)


if __name__ == "__main__":
    main()
