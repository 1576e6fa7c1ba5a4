"""What accumulating `plastic_work` costs the four return mappings: this tree's kernels against a
base commit's (which do not keep it), alternating in one process, on the same states.

    python benchmarks/plastic_work_cost.py --base integration2 [--repeats 9] [--jc]

J2, Drucker-Prager and Mohr-Coulomb update benchmarks/plastic_kernels.py's state (the tall
granular column mid-collapse, tiled to 80,000 particles); with --jc, Johnson-Cook updates
benchmarks/johnson_cook_kernel.py's Taylor bar at 4.8 us (73,950 particles, most yielding;
a minute or more to reach). One thread. Each round calls the base kernel and this tree's
once each, on fresh copies, in alternating order; the table gives the medians (ns per
particle) and the median and range of the ratios base/this (below 1: this tree is slower),
whether the stresses agree bit for bit, and the fastest call of each (the one least
disturbed by the other sessions' load).
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numba
import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import base_kernels  # noqa: E402
from geomaterials import MODELS  # noqa: E402
from plastic_kernels import column_state, row  # noqa: E402
from solver import materials  # noqa: E402
from solver.materials.kernels import drucker_prager, j2_plasticity, johnson_cook, mohr_coulomb  # noqa: E402

THIS = {"j2_plasticity": j2_plasticity, "drucker_prager": drucker_prager, "mohr_coulomb": mohr_coulomb,
        "johnson_cook": johnson_cook}


def column_calls(name: str, model, p, dt: float, tiles: int = 50):
    """(base arguments, this tree's arguments) makers of the kernel `name` on the tiled column."""
    L, stress, volume = np.tile(p.L, (tiles, 1, 1)), np.tile(p.stress, (tiles, 1, 1)), np.tile(p.volume, tiles)
    n = L.shape[0]
    if name == "j2_plasticity":
        tail = (dt, model.bulk, model.mu, model.yield_stress, model.hardening, 1)
        return (lambda: (L.copy(), stress.copy(), np.zeros(n), *tail),
                lambda: (L.copy(), stress.copy(), np.zeros(n), volume, np.zeros(n), *tail))
    if name == "drucker_prager":
        tail = (dt, model.bulk, model.mu, model.eta, model.eta_bar, model.xi_c, model.tension_cutoff, 1)
    else:
        tail = (dt, model.bulk, model.mu, model.sin_phi, model.sin_psi, model.cohesion, model.tension_cutoff, 1)
    return (lambda: (L.copy(), stress.copy(), np.zeros(n), np.zeros(n), *tail),
            lambda: (L.copy(), stress.copy(), np.zeros(n), np.zeros(n), volume, np.zeros(n), *tail))


def bar_calls(dt_at: float):
    """The same for Johnson-Cook on the Taylor bar at `dt_at` seconds."""
    from johnson_cook_kernel import kernel_args
    from karamelo_anchor import anchor_scene

    from solver.scene_checks import load_scene
    from solver.stepper import ExplicitMPM
    scene = anchor_scene(1e-4)
    scene["parallel"] = {"threads": 1}
    sim, t = ExplicitMPM(load_scene(scene)), 0.0
    while t < dt_at:
        dt = sim.stable_time_step(0.5)
        sim.advance(dt)
        t += dt
    n = sim.particles.count

    def base():
        args = kernel_args(sim, dt)
        return (*args[:7], *args[8:])       # without the plastic work
    return base, (lambda: kernel_args(sim, dt)), n


def compare(base, this, make_base, make_this, count: int, repeats: int) -> dict:
    times, stresses = {"base": [], "this": []}, {}
    for round_ in range(repeats + 1):            # round 0: compile, and the bits
        order = [("base", base, make_base), ("this", this, make_this)]
        for variant, module, make in (order if round_ % 2 == 0 else order[::-1]):
            args = make()
            start = time.perf_counter()
            module._update(*args)
            elapsed = time.perf_counter() - start
            if round_ == 0:
                stresses[variant] = args[1]
            else:
                times[variant].append(elapsed / count * 1e9)
    return {"times": times, "same_bits": bool(np.array_equal(stresses["base"], stresses["this"]))}


def report(name: str, result: dict) -> None:
    """The row, and the fastest call of each (the least disturbed by other load)."""
    best = {variant: min(times) for variant, times in result["times"].items()}
    print(row(name, result) + f" fastest: base {best['base']:.1f}, this {best['this']:.1f}, "
          f"base/this {best['base'] / best['this']:.3f}", flush=True)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--base", default="integration2")
    parser.add_argument("--repeats", type=int, default=9)
    parser.add_argument("--jc", action="store_true", help="also Johnson-Cook on the Taylor bar (slow to set up)")
    args = parser.parse_args()
    numba.set_num_threads(1)
    print("| model | base (ns/particle) | this (ns/particle) | base/this median (range) | same bits |\n"
          "|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        p, dt = column_state()
        for name in ("j2_plasticity", "drucker_prager", "mohr_coulomb"):
            config = MODELS[name]
            model = materials.create(materials.REGISTRY[config["model"]].schema.model_validate(config), 2)
            make_base, make_this = column_calls(name, model, p, dt)
            base = base_kernels.load(args.base, name, Path(folder))
            report(name, compare(base, THIS[name], make_base, make_this, 50 * p.count, args.repeats))
        if args.jc:
            make_base, make_this, n = bar_calls(4.8e-6)
            base = base_kernels.load(args.base, "johnson_cook", Path(folder))
            report("johnson_cook", compare(base, johnson_cook, make_base, make_this, n, args.repeats))
    return 0


if __name__ == "__main__":
    sys.exit(main())
