"""The plastic models' stress updates (J2, Drucker-Prager, Mohr-Coulomb): this tree's kernels
against a base commit's, alternating in one process, on the kernel alone and on whole steps.

    python benchmarks/plastic_kernels.py --base main [--repeats 7] [--steps 100]

The state is benchmarks/geomaterials.py's: the tall granular column run with
Drucker-Prager to mid-collapse (elastic, yielding and apex particles), tiled to 80,000
particles; each model's update_stress runs on copies of it with the base's kernel and
with this tree's, taking turns (ns per particle, median of `repeats` and the range of the
ratios base/this, above 1: this tree is faster); the two stresses are compared bit for
bit. (The base must call its kernels as this tree does: from the commit that added
`plastic_work` on; benchmarks/plastic_work_cost.py compares across that change.) Then the column with each material is stepped twice from the same start, one twin
per kernel, alternately (ns per particle-step, ratios likewise) and the twins' positions
compared bit for bit.
"""
from __future__ import annotations

import argparse
import copy
import statistics
import sys
import tempfile
import time
from pathlib import Path
from types import SimpleNamespace

import numba
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import base_kernels  # noqa: E402
from geomaterials import MODELS, scene_with  # noqa: E402
from solver import materials  # noqa: E402
from solver.materials.kernels import drucker_prager, j2_plasticity, mohr_coulomb  # noqa: E402
from solver.scene_checks import load_scene  # noqa: E402
from solver.stepper import ExplicitMPM  # noqa: E402

MODULES = {"j2_plasticity": j2_plasticity, "drucker_prager": drucker_prager, "mohr_coulomb": mohr_coulomb}


def column_state():
    sim = ExplicitMPM(load_scene(scene_with(MODELS["drucker_prager"])))
    dt = sim.stable_time_step(0.5)
    while sim.time < 0.15:
        sim.advance(dt)
    return sim.particles, dt


def kernel_costs(kernels: dict, repeats: int) -> dict:
    """{model: {variant: [ns per particle]}} and whether the two variants' stresses agree bit for bit."""
    p, dt = column_state()
    tiles = 50
    L0, stress0 = np.tile(p.L, (tiles, 1, 1)), np.tile(p.stress, (tiles, 1, 1))
    count = L0.shape[0]
    fake = copy.copy(p)
    fake.volume = np.tile(p.volume, tiles)
    out = {}
    for name, config in MODELS.items():
        model = materials.create(materials.REGISTRY[config["model"]].schema.model_validate(config), 2)
        times, stresses = {variant: [] for variant in kernels[name]}, {}
        for round_ in range(repeats + 1):                   # round 0: compile, and the bits
            for variant, module in kernels[name].items():
                MODULES[name]._update = module._update
                fake.extra = {key: np.zeros(count) for key in ("plastic_strain", "yield_state", "plastic_work")}
                fake.L, fake.stress = L0.copy(), stress0.copy()
                start = time.perf_counter()
                model.update_stress(fake, slice(0, count), dt)
                if round_ == 0:
                    stresses[variant] = fake.stress.copy()
                else:
                    times[variant].append((time.perf_counter() - start) / count * 1e9)
        MODULES[name]._update = kernels[name]["this"]._update
        out[name] = {"times": times, "same_bits": bool(np.array_equal(stresses["base"], stresses["this"]))}
    return out


def step_costs(kernels: dict, repeats: int, steps: int) -> dict:
    """{model: {variant: [ns per particle-step]}} of the column, one twin per kernel."""
    out = {}
    for name, config in MODELS.items():
        twins = {variant: ExplicitMPM(load_scene(scene_with(config))) for variant in kernels[name]}
        dt = twins["this"].stable_time_step(0.5)
        times = {variant: [] for variant in twins}
        for _ in range(repeats + 1):
            for variant, sim in twins.items():
                MODULES[name]._update = kernels[name][variant]._update
                start = time.perf_counter()
                for _ in range(steps):
                    sim.advance(dt)
                times[variant].append((time.perf_counter() - start) / steps / sim.particles.count * 1e9)
        MODULES[name]._update = kernels[name]["this"]._update
        same = np.array_equal(twins["base"].particles.x, twins["this"].particles.x)
        out[name] = {"times": {v: t[1:] for v, t in times.items()}, "same_bits": bool(same)}
    return out


def row(name: str, result: dict) -> str:
    base, this = result["times"]["base"], result["times"]["this"]
    ratios = [b / t for b, t in zip(base, this)]
    return (f"| {name} | {statistics.median(base):.1f} | {statistics.median(this):.1f} | "
            f"{statistics.median(ratios):.2f} ({min(ratios):.2f}-{max(ratios):.2f}) | "
            f"{'yes' if result['same_bits'] else 'NO'} |")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--base", default="main")
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--steps", type=int, default=100)
    args = parser.parse_args()
    numba.set_num_threads(1)
    with tempfile.TemporaryDirectory() as folder:
        # "this" holds the function itself: the module's _update is what gets patched per variant
        kernels = {name: {"base": base_kernels.load(args.base, name, Path(folder)),
                          "this": SimpleNamespace(_update=module._update)} for name, module in MODULES.items()}
        header = "| model | base (ns) | this (ns) | base/this median (range) | same bits |\n|---|---|---|---|---|"
        print("stress update alone, ns per particle:\n" + header)
        for name, result in kernel_costs(kernels, args.repeats).items():
            print(row(name, result))
        print(f"whole steps of the column, ns per particle-step ({args.steps} steps a turn):\n" + header)
        for name, result in step_costs(kernels, args.repeats, args.steps).items():
            print(row(name, result))
    return 0


if __name__ == "__main__":
    sys.exit(main())
