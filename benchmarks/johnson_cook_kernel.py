"""Johnson-Cook's stress update on the Karamelo Taylor bar: this tree's kernel against a base commit's,
alternating in one process, and the whole step with either kernel.

    python benchmarks/johnson_cook_kernel.py                  # against main
    python benchmarks/johnson_cook_kernel.py --base 2e9cfab --rounds 9 --steps 10

The bar of benchmarks/karamelo_anchor.py (whole, 73,950 particles, one thread) is run to
--at seconds (4.8 us: most particles yield); from that state each kernel updates its own
copy --rounds times, the two taking turns (seconds per call), and the two results are
compared (largest relative difference of the stress and of the plastic strain
increment, over the particles that yield). Then two simulations of the bar, run to that state
side by side, step on alternately, one with each kernel (`--steps` steps per turn, the same dt); the
ratio base/this of the whole step (above 1: this tree is faster) and the two bars'
lengths and diameters at the end. The base's kernel must take the same arguments (from the
commit that added `plastic_work` on; benchmarks/plastic_work_cost.py compares across it).
"""
from __future__ import annotations

import argparse
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
from karamelo_anchor import anchor_scene  # noqa: E402
from solver.materials.kernels import johnson_cook  # noqa: E402
from solver.scene_checks import load_scene  # noqa: E402
from solver.stepper import ExplicitMPM  # noqa: E402


def kernel_args(sim: ExplicitMPM, dt: float) -> tuple:
    """The arguments of the kernel's `_update` for the bar's particles, copied."""
    p, model = sim.particles, sim.materials[0][0]
    x = p.extra
    empty = np.zeros(0)
    return (p.L.copy(), p.stress.copy(), p.mass.copy(), p.volume.copy(), x["plastic_strain"].copy(),
            x["plastic_strain_rate"].copy(), x["temperature"].copy(), np.zeros(p.count), empty, empty, dt, model.mu, model.flow,
            model.eos, model.damage, model.failure, 1)


def compare_kernels(kernels: dict, sim: ExplicitMPM, dt: float, rounds: int) -> dict:
    """Seconds per call of each kernel (alternating), and how far their results differ."""
    results = {}
    for name, module in kernels.items():      # compile, and keep one result each
        args = kernel_args(sim, dt)
        module._update(*args)
        results[name] = args
    times = {name: [] for name in kernels}
    for _ in range(rounds):
        for name, module in kernels.items():
            args = kernel_args(sim, dt)
            start = time.perf_counter()
            module._update(*args)
            times[name].append(time.perf_counter() - start)
    base, this = results["base"], results["this"]
    eps_before = sim.particles.extra["plastic_strain"]
    yielding = this[4] > eps_before
    d_base, d_this = base[4] - eps_before, this[4] - eps_before
    stress_scale = np.abs(base[1]).max(axis=(1, 2))
    return {"times": times, "yielding": int(yielding.sum()),
            "identical": float(np.mean(d_base[yielding] == d_this[yielding])),
            "increment": float(np.max(np.abs(d_this - d_base)[yielding] / d_base[yielding])),
            "stress": float(np.max(np.abs(this[1] - base[1]).max(axis=(1, 2)) / stress_scale))}


def shape(sim: ExplicitMPM) -> tuple[float, float]:
    """The bar's length (y extent) and its largest diameter (x extent), in metres."""
    x = sim.particles.x
    return float(np.ptp(x[:, 1])), float(np.ptp(x[:, 0]))


def compare_steps(kernels: dict, sims: dict, dt: float, rounds: int, steps: int) -> dict:
    """The twins `sims`, one per kernel, stepped alternately: seconds per step, and their shapes."""
    times = {name: [] for name in kernels}
    for _ in range(rounds):
        for name, twin in sims.items():
            johnson_cook._update = kernels[name]._update      # what JohnsonCook.update_stress calls
            start = time.perf_counter()
            for _ in range(steps):
                twin.advance(dt)
            times[name].append((time.perf_counter() - start) / steps)
    johnson_cook._update = kernels["this"]._update
    return {"times": times, "shapes": {name: shape(twin) for name, twin in sims.items()}}


def ratio_line(times: dict) -> str:
    ratios = [b / t for b, t in zip(times["base"], times["this"])]
    return (f"base/this median {statistics.median(ratios):.2f} (range {min(ratios):.2f}-{max(ratios):.2f}); "
            f"this {1e3 * statistics.median(times['this']):.1f} ms, "
            f"base {1e3 * statistics.median(times['base']):.1f} ms")


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--base", default="main", help="the commit whose kernel is the reference")
    parser.add_argument("--at", type=float, default=4.8e-6, help="simulated time of the state measured")
    parser.add_argument("--rounds", type=int, default=9)
    parser.add_argument("--steps", type=int, default=10, help="steps per turn of the whole-step comparison")
    args = parser.parse_args()
    numba.set_num_threads(1)
    scene = anchor_scene(1e-4)
    scene["parallel"] = {"threads": 1}
    twins = {name: ExplicitMPM(load_scene(scene)) for name in ("base", "this")}
    sim, t = twins["this"], 0.0
    while t < args.at:                  # both with this tree's kernel, the same steps
        dt = sim.stable_time_step(0.5)
        for twin in twins.values():
            twin.advance(dt)
        t += dt
    with tempfile.TemporaryDirectory() as folder:
        # "this" holds the function itself: johnson_cook._update is what gets patched per variant
        kernels = {"base": base_kernels.load(args.base, "johnson_cook", Path(folder)),
                   "this": SimpleNamespace(_update=johnson_cook._update)}
        kernel = compare_kernels(kernels, sim, dt, args.rounds)
        print(f"state at {1e6 * t:.2f} us, {sim.particles.count} particles, {kernel['yielding']} yielding")
        print(f"kernel: {ratio_line(kernel['times'])}")
        print(f"  plastic increments of the yielding particles identical for {100 * kernel['identical']:.1f} %; "
              f"largest relative difference: increment {kernel['increment']:.2e}, stress {kernel['stress']:.2e}")
        steps = compare_steps(kernels, twins, dt, args.rounds, args.steps)
    print(f"whole step ({args.steps} steps a turn, {args.rounds} turns): {ratio_line(steps['times'])}")
    (lb, db), (lt, dt_) = steps["shapes"]["base"], steps["shapes"]["this"]
    print(f"  after {args.rounds * args.steps} more steps: length {1e3 * lt:.6f} mm (base {1e3 * lb:.6f}, "
          f"relative difference {abs(lt - lb) / lb:.1e}), diameter {1e3 * dt_:.6f} mm (base {1e3 * db:.6f}, "
          f"{abs(dt_ - db) / db:.1e})")
    return 0


if __name__ == "__main__":
    sys.exit(main())
