"""Heat: the cost of conduction in a step, and the errors and times of the heat
verification cases (the "Heat" section of docs/benchmarks.md).

    python benchmarks/heat.py [--rounds 200] [--threads 1,2] [--skip-cases] [--skip-cost]

Cost: one 2D and one 3D scene (an elastic block, MUSL, linear hats, 58k and 111k
particles), stepped in the same process, for each thread count:

    no heat            the scene without thermal keys (fused backend)
    conduction         the same scene with conduction and a held face (fused: the
                       temperature rides in the fused P2G, REMAP and KINEMATICS passes)
    cond. + expansion  and thermal expansion
    separate passes    conduction + expansion on the general backend, the thermal
                       particle passes apart (solver/thermal_kernels.py): the step before
                       conduction was fused

Each of `rounds` rounds steps every variant once, in a rotating order, so that the
machine's load falls on all alike. Reported per variant: the fastest step and the median
step; per ratio to "no heat": the ratio of the fastest steps (the cost without other
work on the machine: on this shared host a busy neighbour stretches steps by 10-60 %,
and the fastest of a few hundred is where that is least) and, in brackets, the median
of the per-round ratios.

Cases: tests/verification/heat_cases.py (E12 with refinement and [R]'s dt = 8e-5,
E13, the boundary heat balance, the axisymmetric tube, thermal expansion).
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "verification"))

import numpy as np  # noqa: E402

import heat_cases as hc  # noqa: E402

from solver.scene_checks import load_scene  # noqa: E402
from solver.stepper import ExplicitMPM  # noqa: E402

THERMAL = {"thermal_conductivity": 50.0, "specific_heat": 500.0, "thermal_expansion": 1.0e-5}


def block(dim: int, cell: float, heat: bool, threads: int = 0, expansion: bool = True) -> dict:
    material = {"model": "linear_elastic", "density": 8000.0, "youngs_modulus": 2.0e11, "poisson_ratio": 0.3}
    if heat:
        material.update(THERMAL)
        if not expansion:
            del material["thermal_expansion"]
    return {"dimension": dim, "method": {"scheme": "musl"},
            "grid": {"lower": [0.0] * dim, "upper": [1.0] * dim, "cell_size": cell},
            "materials": {"steel": material},
            "bodies": [{"name": "block", "material": "steel", "initial_velocity": [1.0] + [0.0] * (dim - 1),
                        "geometry": {"type": "box", "lower": [0.2] * dim, "upper": [0.8] * dim},
                        "initial_temperature": 300.0}],
            "boundary_conditions": [{"type": "temperature", "face": "x-", "temperature": 400.0}] if heat else [],
            "time": {"end": 1.0}, "parallel": {"threads": threads}}


def one_step(sim: ExplicitMPM, dt: float) -> float:
    start = time.perf_counter()
    sim.advance(dt)
    return time.perf_counter() - start


VARIANTS = ("no heat", "conduction", "cond. + expansion", "separate passes")


def simulations(dim: int, cell: float, threads: int) -> dict[str, ExplicitMPM]:
    sims = {"no heat": ExplicitMPM(load_scene(block(dim, cell, False, threads))),
            "conduction": ExplicitMPM(load_scene(block(dim, cell, True, threads, expansion=False))),
            "cond. + expansion": ExplicitMPM(load_scene(block(dim, cell, True, threads))),
            "separate passes": ExplicitMPM(load_scene(block(dim, cell, True, threads)), general=True)}
    assert [sim.fused for sim in sims.values()] == [True, True, True, False]
    return sims


def step_costs(dim: int, cell: float, rounds: int, threads: int):
    """Seconds of each variant's steps, (rounds,) each: one step of every variant a round."""
    sims = simulations(dim, cell, threads)
    dts = {name: 0.1 * sim.stable_time_step(0.5) for name, sim in sims.items()}
    for name, sim in sims.items():   # compile
        one_step(sim, dts[name])
        one_step(sim, dts[name])
    names = list(sims)
    times = {name: np.empty(rounds) for name in names}
    for r in range(rounds):
        for name in names[r % len(names):] + names[:r % len(names)]:
            times[name][r] = one_step(sims[name], dts[name])
    return times, sims["no heat"].particles.count


def _ratio(times, heat: str, base: str) -> str:
    """ratio of the fastest steps (median of the per-round ratios)"""
    return f"{times[heat].min() / times[base].min():.2f} ({np.median(times[heat] / times[base]):.2f})"


def cost_table(rounds: int, thread_counts: list[int]) -> None:
    print(f"ms per step: fastest (median) of {rounds} steps; ratios to 'no heat': of the fastest steps "
          "(median of the per-round ratios)")
    print("| threads | scene | particles | " + " | ".join(f"{v} (ms)" for v in VARIANTS) + " | "
          + " | ".join(f"{v} / no heat" for v in VARIANTS[1:]) + " |")
    print("|---" * (3 + 2 * len(VARIANTS) - 1) + "|")
    for threads in thread_counts:
        for dim, cell in ((2, 0.005), (3, 0.025)):
            times, particles = step_costs(dim, cell, rounds, threads)
            ms = [f"{1e3 * times[v].min():.2f} ({1e3 * np.median(times[v]):.2f})" for v in VARIANTS]
            ratios = [_ratio(times, v, "no heat") for v in VARIANTS[1:]]
            print(f"| {threads} | {dim}D block, MUSL, linear | {particles} | " + " | ".join(ms + ratios) + " |",
                  flush=True)


def timed(function, *args, **kwargs):
    start = time.perf_counter()
    value = function(*args, **kwargs)
    return value, time.perf_counter() - start


def case_table() -> None:
    print("| case | measure | value | wall (s) |")
    print("|---|---|---|---|")
    previous = None
    for cells in (25, 50, 100):
        h = 1.0 / cells
        errors, wall = timed(hc.bar_errors, cells, 0.5 * h * h / 2)
        worst = max(e[0] for e in errors.values())
        order = "" if previous is None else f", order {math.log2(previous / worst):.2f}"
        print(f"| E12, {cells} cells, dt = h^2/4 | max nodal error over t = 0.0075, 0.03, 0.05 | "
              f"{worst:.2e}{order} | {wall:.2f} |")
        previous = worst
    for dt in (5e-5, 8e-5):
        sim = ExplicitMPM(load_scene(hc.bar_scene(100, 5e-5)))
        start = time.perf_counter()
        hc.advance_to(sim, 0.05, dt)
        wall = time.perf_counter() - start
        nodes = sim.grid.node_positions()[:, 0]
        grid = np.max(np.abs(sim.conduction.grid_temperature() - hc.bar_exact(nodes, sim.time)))
        p = sim.particles
        particles = np.max(np.abs(p.extra["temperature"] - hc.bar_exact(p.x[:, 0], sim.time)))
        print(f"| E12, 100 cells, dt = {dt:g} ([R]; errata F7) | max error at t = 0.05, grid / particles | "
              f"{grid:.2e} / {particles:.2e} | {wall:.2f} |")
    for t in (0.0075, 0.03, 0.05):   # issue 51: the particle next to a held end takes the grid's T~
        ends, wall = timed(hc.held_neighbour_errors, 100, 5e-5, t)
        print(f"| E12, 100 cells, dt = 5e-05, t = {t:g} | the end cells' particles: error (bound) | "
              + ", ".join(f"{e:.1e} ({b:.1e})" for e, b in ends) + f" | {wall:.2f} |")
    previous = None
    for cells, dt in ((10, 1e-4), (20, 1e-4), (40, 2.5e-5)):
        error, wall = timed(hc.plate_error, cells, dt)
        order = "" if previous is None else f", order {math.log2(previous / error):.2f}"
        print(f"| E13, {cells} x {cells} cells, dt = {dt:g} | max nodal error at t = 0.05 (K, of 100) | "
              f"{error:.3f}{order} | {wall:.2f} |")
        previous = error
    for dim in (1, 2, 3):
        (gain, heat_in), wall = timed(hc.flux_balance, dim)
        print(f"| heat flux + convection, {dim}D, 200 steps | abs(gain of sum m c T - heat in) / heat in | "
              f"{abs(gain - heat_in) / heat_in:.1e} | {wall:.2f} |")
    for axisymmetric in (True, False):
        error, wall = timed(hc.tube_error, axisymmetric)
        kind = "axisymmetric" if axisymmetric else "plane (no radial term)"
        print(f"| tube r in [1, 2], {kind}, t = 1 | max nodal distance from ln(r)/ln 2 | {error:.1e} | {wall:.2f} |")
    for model in hc.SOLIDS:
        sim, wall = timed(hc.heated_bar, model, True)
        stress = np.max(np.abs(sim.particles.stress[:, 0, 0] / (-hc.E * hc.ALPHA * hc.HEATING) - 1))
        sim_free, wall_free = timed(hc.heated_bar, model, False)
        strain = abs((sim_free.particles.F[:, 0, 0].mean() - 1) / (hc.ALPHA * hc.HEATING) - 1)
        print(f"| heated bar, {model} | clamped: max rel. error of -E alpha dT; free: of alpha dT | "
              f"{stress:.1e}; {strain:.1e} | {wall + wall_free:.2f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=200, help="steps of each variant, one a round")
    parser.add_argument("--threads", default="1,2", help="thread counts, comma-separated (0: the default count)")
    parser.add_argument("--skip-cases", action="store_true")
    parser.add_argument("--skip-cost", action="store_true")
    args = parser.parse_args()
    if not args.skip_cost:
        cost_table(args.rounds, [int(t) for t in args.threads.split(",")])
    if not args.skip_cases:
        print()
        case_table()


if __name__ == "__main__":
    main()
