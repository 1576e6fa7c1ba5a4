"""Solver throughput in particle-steps per second, side by side with numba, Taichi and Warp.

    python benchmarks/throughput.py                  # the tables of docs/benchmarks.md
    python benchmarks/throughput.py --quick          # smaller problems, fewer steps
    python benchmarks/throughput.py --frameworks-python /path/to/python   # where taichi and warp-lang are
    python benchmarks/throughput.py --side-by-side-only --mls-only --frameworks taichi   # the goals' columns, no Warp

Part 1, the side-by-side comparison of issue 9. One elastic block (80 % of the unit
grid, 2 particles per cell per axis, moving and straining), the same step for all:
quadratic B-splines, APIC, neo-Hookean, float64, at ~32k and ~130k particles in 2D
and ~130k and ~260k in 3D, at 1 and 2 threads:

- this solver's full step (USL, APIC; the fused kernels of solver/fused.py, with
  boundary conditions, energy accounting and every check a run makes);
- the same scene on the solver's general kernels (stored stencils, serial P2G);
- a minimal hand-written numba MLS-MPM step (benchmarks/reference_mls.py);
- Taichi on its CPU backend and NVIDIA Warp on its CPU device
  (benchmarks/frameworks/), each in its own process.

The solver and the numba reference alternate in one process (best of three), so
their ratio holds on a busy machine where absolute numbers do not; the Taichi
and Warp processes run right after, in the same invocation. Taichi and Warp are
not dependencies of the project: `pip install taichi warp-lang` (or the project's
`bench` extra) into the interpreter given by --frameworks-python.

Part 2, the solver's own ceiling: linear shape functions, MUSL, FLIP against the
hand-fused 2D step of benchmarks/reference_mpm2d.py, and the start-up time.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from reference_mls import ReferenceMLS, ReferenceMPM88  # noqa: E402
from reference_mpm2d import ReferenceMPM2D  # noqa: E402
from solver.scene_checks import load_scene  # noqa: E402
from solver.stepper import ExplicitMPM  # noqa: E402

DT = 1e-6


def block_scene(dim: int, cells_per_axis: int) -> dict:
    """A block filling 80 % of the unit grid, 2 particles per cell per axis, moving and straining."""
    h = 1.0 / cells_per_axis
    return {
        "version": 1, "name": f"block-{dim}d", "dimension": dim,
        "method": {"scheme": "musl", "shape_function": "linear", "transfer": "flip", "flip_ratio": 0.99},
        "grid": {"lower": [0.0] * dim, "upper": [1.0] * dim, "cell_size": h},
        "materials": {"m": {"model": "linear_elastic", "density": 1000.0, "youngs_modulus": 1e6, "poisson_ratio": 0.3}},
        "bodies": [{"name": "block", "material": "m", "particles_per_cell": 2,
                    "geometry": {"type": "box", "lower": [0.1] * dim, "upper": [0.9] * dim},
                    "initial_velocity": ["0.1 * sin(3 * x)"] + ["0.05"] * (dim - 1)}],
        "time": {"end": 1.0, "dt": DT},
        "output": {"frames": 2, "fields": ["position"]},
    }


FRAMEWORKS = Path(__file__).resolve().parent / "frameworks"
MLS_DT = 1e-5


def mls_block_scene(dim: int, cells: int, threads: int, transfer: str = "apic") -> dict:
    """The block of the side-by-side comparison: the step every implementation runs
    (the solver's with APIC, and with MLS: the frameworks' and the reference's transfer)."""
    scene = block_scene(dim, cells)
    scene["method"] = {"scheme": "usl", "shape_function": "quadratic_bspline", "transfer": transfer}
    scene["materials"]["m"]["model"] = "neo_hookean"
    scene["time"]["dt"] = MLS_DT
    scene["parallel"] = {"threads": threads}
    return scene


GENERAL = True           # time the general kernels too (--no-general: not)
MLS_ONLY = False         # time only the solver's MLS step and the references (--mls-only)
FRAMEWORKS_RUN = ("taichi", "warp")   # which frameworks' processes run (--frameworks)
MPM88_DT = 1e-4          # Taichi's mpm88 benchmark (n_grid 128, dt 1e-4)
MPM88_BULK = 400.0       # its E: the pressure K (J - 1) of a fluid of density 1
MPM88_GRAVITY = 9.8


def mpm88_scene(threads: int, transfer: str = "mls") -> dict:
    """Taichi's mpm88: a block of weakly compressible fluid (density 1, K = 400, no viscosity)
    falling at 1 m/s under gravity in the unit square, 128 x 128 cells, quadratic B-splines, USL.
    The block is 52 x 52 cells at 7 x 7 particles a cell (132,496 particles; mpm88 drops
    random ones into [0.2, 0.6]^2); walls are slip walls on the faces (mpm88: 3 nodes thick,
    stopping only motion out of the grid, which the block does not reach in the steps measured)."""
    lower, upper = 24 / 128, 76 / 128
    return {
        "version": 1, "name": "mpm88", "dimension": 2,
        "method": {"scheme": "usl", "shape_function": "quadratic_bspline", "transfer": transfer},
        "grid": {"lower": [0.0, 0.0], "upper": [1.0, 1.0], "cell_size": 1 / 128},
        "materials": {"water": {"model": "fluid", "density": 1.0, "bulk_modulus": MPM88_BULK, "gamma": 1.0,
                                "viscosity": 0.0}},
        "bodies": [{"name": "water", "material": "water", "particles_per_cell": 7,
                    "geometry": {"type": "box", "lower": [lower] * 2, "upper": [upper] * 2},
                    "initial_velocity": [0.0, -1.0]}],
        "boundary_conditions": [{"type": "wall", "face": face, "mode": "slip"} for face in ("x-", "x+", "y-", "y+")],
        "gravity": [0.0, -MPM88_GRAVITY],
        "time": {"end": 1.0, "dt": MPM88_DT},
        "output": {"frames": 2, "fields": ["position"]},
        "parallel": {"threads": threads},
    }


def _framework(script: str, args: list[str], python: str, threads: int) -> dict:
    env = {**os.environ, "OMP_NUM_THREADS": str(threads)}
    done = subprocess.run([python, str(FRAMEWORKS / script), *args], capture_output=True, text=True, env=env,
                          timeout=1800)
    if done.returncode != 0:
        tail = done.stderr.strip().splitlines()[-1:] or ["(no output)"]
        raise SystemExit(f"{script} failed with {python}: {tail[0]}\n"
                         f"install the frameworks there: {python} -m pip install taichi warp-lang")
    return json.loads(done.stdout.strip().splitlines()[-1])


def side_by_side(dim: int, cells: int, threads: int, steps: int, python: str, warp_rate: dict) -> dict:
    """Particle-steps/s of the five implementations of one block at one thread count."""
    steppers = _solver_steppers(lambda transfer: mls_block_scene(dim, cells, threads, transfer), "apic")
    p = steppers["mls"].particles
    start_x, start_v = p.x.copy(), p.v.copy()    # for Taichi and Warp, before the solver moves them
    model = steppers["mls"].materials[0][0]
    reference = ReferenceMLS(p.x, p.v, p.mass, p.volume, cells, model.lam, model.mu, threads)
    n = p.count
    best = _alternate({**steppers, "numba": reference}, threads, steps, MLS_DT, n)
    with tempfile.TemporaryDirectory() as tmp:
        block = Path(tmp) / "block.npz"
        save_mls_block(block, start_x, start_v, p, cells, model)
        best |= _frameworks("mls", block, threads, steps, python, warp_rate, (dim, cells))
    return {"case": f"{dim}D block", "dimension": dim, "particles": n, "threads": threads, **best}


def save_mls_block(path: Path, x: np.ndarray, v: np.ndarray, particles, cells: int, model) -> None:
    """The block's state as the frameworks' scripts read it (frameworks/mls_*.py)."""
    np.savez(path, x=x, v=v, mass=particles.mass, volume=particles.volume, cells=cells, lam=model.lam,
             mu=model.mu, dt=MLS_DT)


def side_by_side_mpm88(threads: int, steps: int, python: str, warp_rate: dict) -> dict:
    """Particle-steps/s of the mpm88 fluid: the solver (APIC, MLS, MLS on the general kernels),
    the numba reference `step_mpm88`, Taichi and Warp, on the particles the solver seeded."""
    steppers = _solver_steppers(lambda transfer: mpm88_scene(threads, transfer), "mls")
    p = steppers["mls"].particles
    reference = ReferenceMPM88(p.x, p.v, p.mass, p.volume, 128, MPM88_BULK, MPM88_GRAVITY, threads)
    block = {"x": p.x.copy(), "v": p.v.copy(), "mass": p.mass, "volume": p.volume, "cells": 128,
             "bulk": MPM88_BULK, "gravity": MPM88_GRAVITY, "bound": ReferenceMPM88.BOUND, "dt": MPM88_DT}
    best = _alternate({**steppers, "numba": reference}, threads, steps, MPM88_DT, p.count)
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "mpm88.npz"
        np.savez(path, **block)
        best |= _frameworks("mpm88", path, threads, steps, python, warp_rate, "mpm88")
    return {"case": "mpm88", "dimension": 2, "particles": p.count, "threads": threads, **best}


def _frameworks(stem: str, state: Path, threads: int, steps: int, python: str, warp_rate: dict, key) -> dict:
    """Taichi's and Warp's rates on the state saved in `state` (nan for a framework left out
    with --frameworks); Warp's CPU device runs on one thread, so it runs once per case."""
    rates = {"taichi": float("nan"), "warp": float("nan")}
    if "taichi" in FRAMEWORKS_RUN:
        rates["taichi"] = _framework(f"{stem}_taichi.py", [str(state), str(threads), str(steps)], python,
                                     threads)["rate"]
    if "warp" in FRAMEWORKS_RUN:
        if key not in warp_rate:
            warp_rate[key] = _framework(f"{stem}_warp.py", [str(state), str(steps)], python, 1)["rate"]
        rates["warp"] = warp_rate[key]
    return rates


def _solver_steppers(scene_of, general_transfer: str) -> dict:
    """The solver's steppers this run times, in the table's order, each built only if timed:
    APIC, MLS, MLS unfolded and the general kernels (with `general_transfer`); MLS alone with
    --mls-only, no general kernels with --no-general. scene_of(transfer) gives the scene."""
    steppers = {"mls": ExplicitMPM(load_scene(scene_of("mls")))}
    if MLS_ONLY:
        return steppers
    steppers = {"solver": ExplicitMPM(load_scene(scene_of("apic"))), **steppers,
                "mls_unfolded": _unfolded(scene_of("mls"))}
    if GENERAL:
        steppers["general"] = ExplicitMPM(load_scene(scene_of(general_transfer)))
        steppers["general"].use_general_kernels()
    return steppers


def _unfolded(scene: dict) -> ExplicitMPM:
    """The solver's MLS step as it was before the fused P2G folded dt f_I into the momentum
    (solver/step/fused.py `folds_force`): the force scattered on its own, same step to round-off."""
    sim = ExplicitMPM(load_scene(scene))
    sim.phases.folds_force = lambda: False
    return sim


def _alternate(contenders: dict, threads: int, steps: int, dt: float, n: int) -> dict:
    """Best of three rates of each stepper, taking turns (the general kernels run a quarter of the steps)."""
    import numba

    for stepper in contenders.values():     # compile, and set the thread count each uses
        numba.set_num_threads(threads)
        stepper.advance(dt)
    best = {name: float("nan") for name in ("solver", "mls_unfolded", "general")} | {name: 0.0 for name in contenders}
    for _ in range(3):
        for name, stepper in contenders.items():
            numba.set_num_threads(threads)
            best[name] = max(best[name], rate(stepper, n, steps if name != "general" else max(2, steps // 4), dt))
    return best


def rate(stepper, n_particles: int, steps: int, dt: float = DT) -> float:
    start = time.perf_counter()
    for _ in range(steps):
        stepper.advance(dt)
    return n_particles * steps / (time.perf_counter() - start)


def measure(dim: int, cells: int, steps: int, repeats: int) -> dict:
    scene = block_scene(dim, cells)
    scene["parallel"] = {"threads": 1}
    sim = ExplicitMPM(load_scene(scene))
    n = sim.particles.count
    sim.advance(DT)                       # compile (or load from cache)
    ours = []
    ref_rates = []
    reference = ReferenceMPM2D.from_simulation(sim) if dim == 2 else None
    if reference is not None:
        reference.advance(DT)
    for _ in range(repeats):             # alternate, keep the best of each: the least disturbed run
        ours.append(rate(sim, n, steps))
        if reference is not None:
            ref_rates.append(rate(reference, n, steps))
    row = {"dimension": dim, "particles": n, "grid_nodes": sim.grid.n_nodes, "steps": steps,
           "solver": max(ours)}
    if ref_rates:
        row["reference"] = max(ref_rates)
        row["ratio"] = row["solver"] / row["reference"]
    return row


def startup_seconds() -> float:
    """Wall time of `python -m solver run` on a tiny scene up to the end of its first step, warm cache."""
    scene = block_scene(2, 8)
    scene["time"] = {"end": DT, "dt": DT}
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "tiny.json"
        path.write_text(json.dumps(scene))
        code = ("import time, sys; t0 = time.perf_counter();"
                "from solver.scene_checks import load_scene; from solver.stepper import ExplicitMPM;"
                "sim = ExplicitMPM(load_scene(sys.argv[1])); sim.advance(1e-6);"
                "print(time.perf_counter() - t0)")
        subprocess.run([sys.executable, "-c", code, str(path)], check=True, capture_output=True)   # warm the cache
        start = time.perf_counter()
        subprocess.run([sys.executable, "-c", code, str(path)], check=True, capture_output=True)
        return time.perf_counter() - start


def breakdown(dim: int, cells: int, repeats: int = 5) -> dict:
    """Where the solver's step spends its time, per particle and phase (one thread),
    beside the whole step of the numba MLS reference."""
    import numba

    from solver import kernels

    sim = ExplicitMPM(load_scene(mls_block_scene(dim, cells, 1)))
    p, g = sim.particles, sim.grid
    model = sim.materials[0][0]
    reference = ReferenceMLS(p.x, p.v, p.mass, p.volume, cells, model.lam, model.mu, 1)
    numba.set_num_threads(1)
    for _ in range(2):
        sim.advance(MLS_DT)
        reference.advance(MLS_DT)
    tiny = 1e-12   # phases timed on their own must not move the particles
    phases = {
        "P2G (mass, momentum with APIC, force)": lambda: sim.phases.particles_to_grid(MLS_DT),
        "grid update and boundary conditions": lambda: (kernels.integrate_nodes(
            sim.spec[0], tiny, g.mass, g.momentum, g.force, sim.mass_cutoff, g.v_new),
            sim.phases._constrain(g.v_new)),
        "G2P (v, C, x; L, F, V)": lambda: sim.phases.grid_to_particles(tiny, remap=False, kinematics=True),
        "material (neo-Hookean stress)": lambda: sim.phases.stress(tiny),
        "whole step (with the checks and the energy accounting)": lambda: sim.advance(tiny),
        "numba MLS reference, whole step": lambda: reference.advance(tiny),
    }
    best = {name: np.inf for name in phases}
    reps = max(3, int(3e5 / p.count))
    for _ in range(repeats):
        for name, phase in phases.items():
            start = time.perf_counter()
            for _ in range(reps):
                phase()
            best[name] = min(best[name], (time.perf_counter() - start) / reps / p.count * 1e9)
    return {"dimension": dim, "particles": p.count, "ns_per_particle": best}


def print_breakdown(rows: list[dict]) -> None:
    print("where a step's time goes, ns per particle, one thread")
    for r in rows:
        print(f"  {r['dimension']}D block, {r['particles']:,} particles")
        for name, ns in r["ns_per_particle"].items():
            print(f"    {name:<58}{ns:8.1f}")


def print_side_by_side(rows: list[dict]) -> None:
    print("part 1: the same elastic-block step (quadratic B-splines, APIC, neo-Hookean, float64), "
          "M particle-steps/s")
    head = ("case", "particles", "threads", "solver APIC", "solver MLS", "MLS unfolded", "general", "numba MLS",
            "Taichi", "Warp (1 thr.)", "APIC/numba", "MLS/numba", "MLS/Taichi", "MLS/Warp", "MLS/unfolded")
    print("".join(f"{h:>14}" for h in head))
    for r in rows:
        cells = (r["case"], f"{r['particles']:,}", r["threads"], *(f"{r[k] / 1e6:.2f}" for k in
                 ("solver", "mls", "mls_unfolded", "general", "numba", "taichi", "warp")),
                 f"{r['solver'] / r['numba']:.2f}", *(f"{r['mls'] / r[k]:.2f}" for k in ("numba", "taichi", "warp",
                                                                                        "mls_unfolded")))
        print("".join(f"{c:>14}" for c in cells))


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="small problems, for a smoke run")
    parser.add_argument("--json", type=Path, help="also write the rows as JSON")
    parser.add_argument("--frameworks-python", default=sys.executable,
                        help="the Python that has taichi and warp-lang (default: this one)")
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--skip-part2", action="store_true")
    parser.add_argument("--side-by-side-only", action="store_true", help="part 1 only (no breakdown, no part 2)")
    parser.add_argument("--no-general", action="store_true", help="leave out the general kernels (part 1)")
    parser.add_argument("--mpm88-steps", type=int, default=20,
                        help="steps of each timing on the mpm88 fluid (0: leave it out)")
    parser.add_argument("--mls-only", action="store_true",
                        help="part 1: time only the solver's MLS step beside the references (the goals' columns)")
    parser.add_argument("--frameworks", nargs="*", choices=("taichi", "warp"), default=["taichi", "warp"],
                        help="which frameworks run in part 1 (default both; a framework left out reads nan)")
    parser.add_argument("--blocks", nargs="+", metavar="DIM:CELLS:STEPS",
                        help="the blocks of part 1 (default: 2:112:60 2:225:15 3:32:6 3:40:4)")
    args = parser.parse_args()
    if args.quick:
        blocks = [(2, 56, 20), (3, 16, 5)]
        cases = [(2, 56, 20), (3, 14, 10)]
        repeats = 2
    else:
        # 2D: cells^2 * 0.64 * 4 particles (32,400 and 129,600); 3D: cells^3 * 0.512 * 8 (140,608 and 262,144)
        blocks = [(2, 112, 60), (2, 225, 15), (3, 32, 6), (3, 40, 4)]
        cases = [(2, 112, 100), (2, 225, 40), (3, 32, 20)]
        repeats = 3
    if args.blocks:
        blocks = [tuple(int(v) for v in b.split(":")) for b in args.blocks]
    warp_rate: dict = {}
    global GENERAL, MLS_ONLY, FRAMEWORKS_RUN
    GENERAL = not args.no_general
    MLS_ONLY = args.mls_only
    FRAMEWORKS_RUN = tuple(args.frameworks)
    side = [side_by_side(dim, cells, threads, steps, args.frameworks_python, warp_rate)
            for dim, cells, steps in blocks for threads in args.threads]
    if args.mpm88_steps:
        side += [side_by_side_mpm88(threads, args.mpm88_steps, args.frameworks_python, warp_rate)
                 for threads in args.threads]
    print_side_by_side(side)
    if args.side_by_side_only:
        if args.json:
            args.json.write_text(json.dumps({"side_by_side": side}, indent=2))
        return 0
    parts = [breakdown(dim, cells) for dim, cells in ((2, blocks[0][1]), (3, blocks[2 if len(blocks) > 2 else 1][1]))]
    print()
    print_breakdown(parts)
    rows, start = [], None
    if not args.skip_part2:
        rows = [measure(dim, cells, steps, repeats) for dim, cells, steps in cases]
        print("\npart 2: linear hat functions, MUSL, FLIP, one thread, against the hand-fused 2D step")
        print(f"{'case':<10}{'particles':>11}{'nodes':>10}{'solver Mp-steps/s':>20}{'reference':>12}{'ratio':>8}")
        for r in rows:
            ref = f"{r['reference'] / 1e6:12.2f}" if "reference" in r else f"{'-':>12}"
            ratio = f"{r['ratio']:8.2f}" if "ratio" in r else f"{'-':>8}"
            print(f"{str(r['dimension']) + 'D block':<10}{r['particles']:>11,}{r['grid_nodes']:>10,}"
                  f"{r['solver'] / 1e6:20.2f}{ref}{ratio}")
        start = startup_seconds()
        print(f"start-up to the end of the first step, warm cache: {start:.2f} s")
    if args.json:
        args.json.write_text(json.dumps({"side_by_side": side, "breakdown": parts, "rows": rows,
                                         "startup_seconds": start}, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
