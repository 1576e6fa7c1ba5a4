"""The cost of a tool (solver/tools.py) against the same scene without one, side by side.

    python benchmarks/tools_cost.py                        # 1 thread, 5 repeats of 100 steps
    python benchmarks/tools_cost.py --cells 160 --repeats 7

The scene: an elastic slab (the machining workpiece's proportions, 1 x 0.3, --cells x
--cells/4 cells, 1 particle per cell as Karamelo's machining, TLMPM) and, in the second
variant, a wedge-shaped polygon tool cutting it at 0.15 depth and moving along it. Both are
advanced until the tool is in the slab, then timed over --steps steps alternately, --repeats
times each; the table gives each variant's median time per step, the ratio, and the spread
(max/min - 1 of the repeats: the machine's noise at that moment).
"""
from __future__ import annotations

import argparse
import statistics
import time


def scene(cells: int, tool: bool) -> dict:
    h = 1.0 / cells
    out = {
        "dimension": 2, "method": {"formulation": "tlmpm", "scheme": "musl", "shape_function": "linear",
                                   "transfer": "flip", "flip_ratio": 0.99},
        "grid": {"lower": [0.0, 0.0], "upper": [1.0, 0.3], "cell_size": h},
        "materials": {"steel": {"model": "linear_elastic", "density": 7750, "youngs_modulus": 211e9,
                                "poisson_ratio": 0.33}},
        "bodies": [{"name": "work", "material": "steel", "particles_per_cell": 1,
                    "geometry": {"type": "box", "lower": [0.0, 0.0], "upper": [1.0, 0.3]}}],
        "boundary_conditions": [{"type": "wall", "face": "y-", "mode": "stick"}],
        "parallel": {"threads": 1},
        "time": {"end": 1.0},
    }
    if tool:
        out["tools"] = [{"name": "cutter", "geometry": {"type": "polygon", "vertices": [
            [1.0, 0.15], [1.15, 0.15], [1.15, 0.45], [1.05, 0.45]]}, "velocity": [-50.0, 0.0], "stiffness": 1.0}]
    return out


def timed(sim, steps: int) -> float:
    dt = sim.stable_time_step(0.5)
    start = time.perf_counter()
    for _ in range(steps):
        sim.advance(dt)
    return (time.perf_counter() - start) / steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, default=160)
    parser.add_argument("--steps", type=int, default=100)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    from solver.scene_checks import load_scene
    from solver.stepper import ExplicitMPM
    sims = {name: ExplicitMPM(load_scene(scene(args.cells, name == "tool"))) for name in ("bare", "tool")}
    for sim in sims.values():   # compile, and bring the tool into the slab
        timed(sim, 2 * args.steps)
    times = {name: [] for name in sims}
    for _ in range(args.repeats):
        for name, sim in sims.items():
            times[name].append(timed(sim, args.steps))
    pushed = sum(rows.size for _, rows, _ in sims["tool"].tools.pushed)
    median = {name: statistics.median(values) for name, values in times.items()}
    print(f"particles {sims['bare'].particles.count}, pushed by the tool {pushed}")
    for name, values in times.items():
        print(f"{name}: {median[name] * 1e6:.0f} us/step (spread {max(values) / min(values) - 1:.0%})")
    print(f"tool / bare: {median['tool'] / median['bare']:.3f}")


if __name__ == "__main__":
    main()
