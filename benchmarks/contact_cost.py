"""The cost of contact with a field per body against the single field, side by side.

    python benchmarks/contact_cost.py                    # two disks (E2) in contact, 1 thread
    python benchmarks/contact_cost.py --scale 4 --repeats 5 --threads 2

The scene is examples/two_disks.json (--scale k: cells k times smaller and the disks'
particles k^2 times more), advanced to t = 1.55 s, where the disks touch (from 1.525 s), then timed over
--steps steps in three variants, alternately, --repeats times each: the single field as
the scene steps it (the fused backend), the single field on the general backend, and
`"contact": {"model": "friction", "friction": 0.3}` on the backend the scene gets (the
fused one with the default mass-gradient normals; its line names it). The table
gives each variant's median time per step and the ratios contact / single field; the
spread is max/min - 1 of the repeats (the machine's noise at that moment).

--heat adds a fourth variant, contact with conduction (the disks at 400 and 300 K,
k = 1, c = 1000: solver/thermal.py's exchange at the contact nodes and the frictional
heat), and its ratio to contact without heat.
"""
from __future__ import annotations

import argparse
import copy
import json
import statistics
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def scene(scale: int, threads: int, contact: bool, heat: bool = False) -> dict:
    s = json.loads((ROOT / "examples" / "two_disks.json").read_text())
    if heat:
        s["materials"]["elastic"].update(thermal_conductivity=1.0, specific_heat=1000.0)
        for body, T in zip(s["bodies"], (400.0, 300.0)):
            body["initial_temperature"] = T
    s["grid"]["cell_size"] /= scale
    s["time"]["dt"] /= scale
    s["parallel"] = {"threads": threads}
    if contact:
        s["contact"] = {"model": "friction", "friction": 0.3}
    return s


def placed(variant: str, scale: int, threads: int):
    from solver.scene_checks import load_scene
    from solver.stepper import ExplicitMPM
    s = load_scene(scene(scale, threads, variant.startswith("contact"), variant == "contact-heat"))
    sim = ExplicitMPM(s, general=variant == "general")
    while sim.time < 1.55:   # the disks touch from 1.525 s
        sim.advance(s.time.dt)
    return sim, s.time.dt


def time_per_step(sim, dt: float, steps: int) -> float:
    state = copy.deepcopy(sim.particles)   # every repeat steps the same stretch of the impact
    start = time.perf_counter()
    for _ in range(steps):
        sim.advance(dt)
    elapsed = (time.perf_counter() - start) / steps
    sim.particles.replace(state.arrays())
    sim.time -= steps * dt
    sim._place_particles()
    return elapsed


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scale", type=int, default=1)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--heat", action="store_true", help="also contact with conduction")
    args = parser.parse_args()
    variants = ("fused", "general", "contact") + (("contact-heat",) if args.heat else ())
    sims = {v: placed(v, args.scale, args.threads) for v in variants}
    for v in variants:
        time_per_step(*sims[v], 10)   # warm
    times = {v: [] for v in variants}
    for _ in range(args.repeats):
        for v in variants:
            times[v].append(time_per_step(*sims[v], args.steps))
    particles = sims["contact"][0].particles.count
    print(f"two disks x{args.scale}: {particles} particles, {args.threads} thread(s), {args.steps} steps, "
          f"{args.repeats} repeats")
    median = {v: statistics.median(t) for v, t in times.items()}
    for v in variants:
        spread = max(times[v]) / min(times[v]) - 1
        backend = sims[v][0].phases.name
        print(f"  {v:12s} {median[v] * 1e6:9.1f} us/step   spread {spread:5.1%}   ({backend})")
    print(f"  contact / single field (fused)   {median['contact'] / median['fused']:.2f}")
    print(f"  contact / single field (general) {median['contact'] / median['general']:.2f}")
    if args.heat:
        print(f"  contact with heat / contact      {median['contact-heat'] / median['contact']:.2f}")


if __name__ == "__main__":
    main()
