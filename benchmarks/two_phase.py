"""Saturated soil: the cost of the pore fluid in a step, and the errors and times of the
two-phase verification cases (the "Saturated soil" section of docs/benchmarks.md).

    python benchmarks/two_phase.py [--rounds 100] [--threads 1] [--skip-cases]

Cost: a 2D and a 3D layer of Drucker-Prager soil at rest under gravity (geostatic stress,
MUSL, linear hats), stepped in the same process:

    dry (fused)     the scene without its pore fluid: the fused backend, what a dry run takes
    dry (general)   the same on the general backend (stored stencils)
    saturated       the scene with its pore fluid, hydrostatic pore pressure and a drained top,
                    on the fused backend, as it runs (its pore passes form their own stencils)
    saturated (general)   the same on the general backend, as a scene the fused kernels do not
                    take runs (axisymmetry, a rigid footing, another shape function)

Each of `rounds` rounds steps every variant once, in a rotating order, so that the machine's
load falls on all alike; the step size is the same for all (the saturated one's). Reported per
variant: the fastest and the median step; per ratio: the ratio of the fastest steps and, in
brackets, the median of the per-round ratios.

Cases: tests/verification/pore_fluid_cases.py (Terzaghi on 10, 20, 40 cells, in 3D, each soil
model; the undrained response of water and of a softer fluid; the fast wave's speed).
"""
from __future__ import annotations

import argparse
import copy
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "verification"))

import numpy as np  # noqa: E402

import pore_fluid_cases as pc  # noqa: E402
from heat import one_step, timed  # noqa: E402   (benchmarks/heat.py: the same step timing)

from solver.scene_checks import load_scene  # noqa: E402
from solver.stepper import ExplicitMPM  # noqa: E402

WATER = {"bulk_modulus": 2.2e9, "density": 1000.0, "hydraulic_conductivity": 1.0e-5, "porosity": 0.4}
VARIANTS = ("dry (fused)", "dry (general)", "saturated", "saturated (general)")


def layer(dim: int, cell: float, threads: int) -> dict:
    """A layer 1 wide (and deep) and 0.5 high, under its water table, drained at its top."""
    upper = [1.0] * (dim - 1) + [0.5]
    soil = {"model": "drucker_prager", "density": 2000.0, "youngs_modulus": 1.0e7, "poisson_ratio": 0.3,
            "friction_angle": 30.0, "cohesion": 1000.0, "pore_fluid": dict(WATER)}
    walls = [{"type": "wall", "face": f"{'xyz'[a]}{side}", "mode": "slip"} for a in range(dim) for side in "-+"
             if not (a == dim - 1 and side == "+")]
    return {"dimension": dim, "method": {"scheme": "musl"},
            "grid": {"lower": [0.0] * dim, "upper": upper, "cell_size": cell},
            "materials": {"soil": soil}, "gravity": [0.0] * (dim - 1) + [-9.81],
            "bodies": [{"name": "soil", "material": "soil", "geometry": {"type": "box", "lower": [0.0] * dim,
                                                                          "upper": upper},
                        "initial_stress": {"type": "geostatic"},
                        "initial_pore_pressure": {"type": "hydrostatic", "water_table": 0.5}}],
            "boundary_conditions": walls + [{"type": "pore_pressure", "face": f"{'xyz'[dim - 1]}+", "pressure": 0.0}],
            "time": {"end": 1.0}, "parallel": {"threads": threads}}


def dry(scene: dict) -> dict:
    out = copy.deepcopy(scene)
    del out["materials"]["soil"]["pore_fluid"]
    del out["bodies"][0]["initial_pore_pressure"]
    out["boundary_conditions"] = [c for c in out["boundary_conditions"] if c["type"] != "pore_pressure"]
    return out


def step_costs(dim: int, cell: float, rounds: int, threads: int):
    wet = layer(dim, cell, threads)
    sims = {"dry (fused)": ExplicitMPM(load_scene(dry(wet))),
            "dry (general)": ExplicitMPM(load_scene(dry(wet)), general=True),
            "saturated": ExplicitMPM(load_scene(wet)),
            "saturated (general)": ExplicitMPM(load_scene(wet), general=True)}
    assert [sim.fused for sim in sims.values()] == [True, False, True, False]
    dt = sims["saturated"].stable_time_step(0.5)
    for sim in sims.values():   # compile
        one_step(sim, dt)
        one_step(sim, dt)
    names = list(sims)
    times = {name: np.empty(rounds) for name in names}
    for r in range(rounds):
        for name in names[r % len(names):] + names[:r % len(names)]:
            times[name][r] = one_step(sims[name], dt)
    return times, sims["saturated"].particles.count


def _ratio(times, variant: str, base: str) -> str:
    return f"{times[variant].min() / times[base].min():.2f} ({np.median(times[variant] / times[base]):.2f})"


def cost_table(rounds: int, threads: int) -> None:
    print(f"ms per step: fastest (median) of {rounds} steps, {threads} thread(s)")
    print("| scene | particles | " + " | ".join(f"{v} (ms)" for v in VARIANTS)
          + " | saturated / dry (fused) | saturated (general) / dry (general) |")
    print("|---" * (2 + len(VARIANTS) + 2) + "|")
    for dim, cell in ((2, 0.005), (3, 0.04)):
        times, particles = step_costs(dim, cell, rounds, threads)
        ms = [f"{1e3 * times[v].min():.2f} ({1e3 * np.median(times[v]):.2f})" for v in VARIANTS]
        print(f"| {dim}D layer, MUSL, linear | {particles} | " + " | ".join(ms) + " | "
              f"{_ratio(times, 'saturated', 'dry (fused)')} | {_ratio(times, 'saturated (general)', 'dry (general)')} |",
              flush=True)


def case_table() -> None:
    print("| case | U - U_exact at Tv = 0.05 / 0.197 / 0.848 | max abs(p - p_exact) / q at the same Tv | wall (s) |")
    print("|---|---|---|---|")
    runs = [(f"Terzaghi, {cells} cells, 2D, drucker_prager", dict(cells=cells)) for cells in (10, 20, 40)]
    runs += [("Terzaghi, 10 cells, 3D", dict(cells=10, dim=3))]
    runs += [(f"Terzaghi, 10 cells, 2D, {model}", dict(cells=10, model=model))
             for model in ("mohr_coulomb", "linear_elastic")]
    for label, kwargs in runs:
        measured, wall = timed(pc.consolidation, **kwargs)
        degrees = " / ".join(f"{u - pc.terzaghi_degree(tv):+.4f}" for tv, (u, _) in measured.items())
        errors = " / ".join(f"{e:.4f}" for _, e in measured.values())
        print(f"| {label} | {degrees} | {errors} | {wall:.1f} |", flush=True)
    print()
    print("| case | water's share p / (p - sigma'_zz) | exact | mean p / q | wall (s) |")
    print("|---|---|---|---|---|")
    for label, fluid, end in (("water, K_w / n = 4400 E_oed", pc.WATER, 0.02),
                              ("soft fluid, K_w / n = 3 E_oed", {**pc.FLUID, "hydraulic_conductivity": 1e-8}, 0.5)):
        (share, mean, exact), wall = timed(pc.undrained, fluid, end)
        print(f"| undrained, {label} | {share:.6f} | {exact:.6f} | {mean:.6f} | {wall:.1f} |", flush=True)
    print()
    print("| seepage to rest, 10 cells, Tv = 2.5 | max abs(p - rho_w g (H - z)) / (rho_w g H) | wall (s) |")
    print("|---|---|---|")
    for label, as_body_force in (("gravity", False), ("gravity as body_force", True)):
        error, wall = timed(pc.seepage_to_hydrostatic, gravity_as_body_force=as_body_force)
        print(f"| {label} | {np.abs(error).max():.4f} | {wall:.1f} |", flush=True)
    print()
    print("| cells | front speed (m/s) | exact c (m/s) | error | front spreading (the tolerance) | wall (s) |")
    print("|---|---|---|---|---|---|")
    for cells in (10, 20, 40, 80):
        (speed, exact, spreading), wall = timed(pc.fast_wave, cells)
        print(f"| {cells} | {speed:.2f} | {exact:.2f} | {(speed - exact) / exact:+.4f} | {spreading:.4f} | {wall:.2f} |",
              flush=True)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=100, help="steps of each variant, one a round")
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--skip-cases", action="store_true")
    args = parser.parse_args()
    cost_table(args.rounds, args.threads)
    if not args.skip_cases:
        print()
        case_table()


if __name__ == "__main__":
    main()
