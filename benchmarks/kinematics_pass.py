"""MUSL's KINEMATICS pass in 2D: the scalar `g2p` against the vectorised `g2p_kinematics`
(solver/fused_template.py `_g2p_kinematics`; measured in docs/benchmarks.md at 486d120).

    python benchmarks/kinematics_pass.py [--repeats 11] [--threads 1]

On the FLIP block of benchmarks/throughput.py (2D, 225 x 225 cells, 129,600 particles, linear
hats, MUSL, FLIP 0.99, linear elasticity), the state after three steps.

Part 1, the pass alone (ns per particle, best and median of the repeats, each variant timed in
turn within a repeat, the state put back before each):
  - `g2p, stress updated in it`: the scalar pass with the material's update lines (`updates`),
    what the step ran before;
  - `g2p + material's pass`: the scalar pass without them, then the material's own stress pass;
  - `g2p_kinematics + material's pass`: what the step runs now.
and whether x, F, L and V come out the same bits in all three (the stress too, with MPM_FMA=0).
Part 2, whole steps: two simulations of the scene, one with `g2p_kinematics` turned off (so the
stress is updated in the scalar pass again), taking turns, 10 steps a repeat (us a step, best and
median), and whether their positions are the same bits after them.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import numba  # noqa: E402

from solver import fused  # noqa: E402
from solver.scene_checks import load_scene  # noqa: E402
from solver.step.fused import _flat  # noqa: E402
from solver.stepper import ExplicitMPM  # noqa: E402
from throughput import DT, block_scene  # noqa: E402

FIELDS = ("x", "F", "L", "stress", "volume")


def flip_block(threads: int) -> ExplicitMPM:
    scene = block_scene(2, 225)
    scene["parallel"] = {"threads": threads}
    return ExplicitMPM(load_scene(scene))


def _timed(calls: dict, per: int, repeats: int, before) -> dict:
    times = {name: [] for name in calls}
    for _ in range(repeats):
        for name, call in calls.items():
            before()
            start = time.perf_counter()
            call()
            times[name].append((time.perf_counter() - start) / per)
    return times


def _print(title: str, times: dict, unit: str, scale: float) -> None:
    print(title)
    for name, t in times.items():
        print(f"  {name:<36} best {min(t) * scale:8.2f}   median {np.median(t) * scale:8.2f} {unit}")


def part_pass(sim: ExplicitMPM, repeats: int) -> None:
    ph, p, g = sim.phases, sim.particles, sim.grid
    saved = {name: getattr(p, name).copy() for name in FIELDS}

    def restore():
        for name, a in saved.items():
            getattr(p, name)[...] = a

    def scalar(updates: bool):
        ph._g2p_kernel(DT, fused.KINEMATICS, False, updates)
        if not updates:
            ph._material_stress(DT)

    def vectorised():
        ph._kernels.g2p_kinematics(ph._support, *_flat(p.x, sim.rate, p.stored("L"), p.F, g.v_new), p.volume,
                                   p.volume0, *ph._frame, DT, sim.copies.momentum.shape[0] + 1, ph._bad)
        ph._material_stress(DT)
    calls = {"g2p, stress updated in it": lambda: scalar(True), "g2p + material's pass": lambda: scalar(False),
             "g2p_kinematics + material's pass": vectorised}
    results = []
    for call in calls.values():
        restore()
        call()
        results.append({name: getattr(p, name).copy() for name in FIELDS})
    same = {name: all(np.array_equal(r[name], results[0][name]) for r in results) for name in FIELDS}
    _print(f"KINEMATICS pass, {p.count:,} particles (the same bits: {same})",
           _timed(calls, p.count, repeats, restore), "ns/particle", 1e9)
    restore()


def part_steps(threads: int, repeats: int) -> None:
    split, scalar = flip_block(threads), flip_block(threads)
    scalar.phases.replan(without=("g2p_kinematics",))
    for sim in (split, scalar):
        for _ in range(3):
            sim.advance(DT)

    def steps(sim):
        for _ in range(10):
            sim.advance(DT)
    times = _timed({"g2p_kinematics + material's pass": lambda: steps(split),
                    "g2p, stress updated in it": lambda: steps(scalar)}, 10, repeats, lambda: None)
    same = np.array_equal(split.particles.x, scalar.particles.x)
    _print(f"whole steps, {threads} thread(s) (positions the same bits after them: {same})", times, "us/step", 1e6)
    ratio = np.median(times["g2p, stress updated in it"]) / np.median(times["g2p_kinematics + material's pass"])
    print(f"  ratio of the medians (scalar / vectorised): {ratio:.3f}")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=11)
    parser.add_argument("--threads", type=int, default=1)
    args = parser.parse_args()
    numba.set_num_threads(args.threads)
    sim = flip_block(args.threads)
    for _ in range(3):
        sim.advance(DT)
    assert sim.phases.plan.g2p_kinematics == "g2p_kinematics", "the FLIP block's KINEMATICS pass should be `g2p_kinematics`"
    part_pass(sim, args.repeats)
    part_steps(args.threads, args.repeats)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
