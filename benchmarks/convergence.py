"""Speed against error: manufactured solutions over refinements, for every method.

    python benchmarks/convergence.py            # the docs' tables (< 20 min on an idle core: the
                                                #  step times below add up to about 10 min)
    python benchmarks/convergence.py --quick    # 2-3 coarse levels, linear/cubic/Bernstein only (a few min)

For each case (E5 unit segment, E6 unit square, E7 vortex: solver/manufactured.py)
and each valid method (formulation x shape function x transfer) it runs the scene
through `solver.run` at 2-5 cell sizes h and prints a markdown table of h, the
error e2 (and e1), the observed order between successive levels, the wall time of
the run and the particle-steps per second. It writes one plot per case of error
against wall time to docs/images/convergence_<case>.png: the Pareto front a user
picks a method from.

A level that goes unstable is reported as such and the finer ones still run.
Methods a case cannot run are left out and listed: Bernstein with ulmpm (scene
validation), quadratic B-splines on the segment and the square (no
boundary-modified variant: the bodies touch the grid ends, where the rollers are).
The scenes are stepped directly (no output files; the error is sampled at 21
times as the tests sample the result frames) and every method is compiled before
its timings. The time is the CPU time of the steps: the kernels run on one
thread, so it is the wall time an idle machine takes, which a shared machine's
wall clock is not.
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from solver.manufactured import (  # noqa: E402
    R_OUT, Options, cube_displacement, cube_scene, vortex_displacement, vortex_scene,
)
from solver.norms import DisplacementErrors, observed_orders  # noqa: E402
from solver.scene import SceneError  # noqa: E402
from solver.scene_checks import load_scene  # noqa: E402
from solver.stepper import ExplicitMPM, Instability  # noqa: E402

G = 0.05


def with_grid_box(scene: dict) -> dict:
    """ulmpm needs the grid's corners: the padded box tlmpm would use by default."""
    h = scene["grid"]["cell_size"]
    scene["grid"].update(lower=[-R_OUT - 2 * h] * 2, upper=[R_OUT + 2 * h] * 2)
    return scene


class Case:
    def __init__(self, name, title, build, displacement, levels, quick_levels, flip_ratio):
        self.name, self.title, self.build, self.displacement = name, title, build, displacement
        self.levels, self.quick_levels, self.flip_ratio = levels, quick_levels, flip_ratio


CASES = [
    # [R] 6 uses pure FLIP for E5 and the PIC/FLIP blend 0.99 for E6 and E7; the vortex
    # takes 8x more steps per cell (its dt), and the 1 % PIC per step then dominates its
    # error (tests/verification/test_mms_vortex.py), so it runs with pure FLIP here too.
    Case("segment", "E5 unit segment (1D, G = 0.05, one period)",
         lambda h, o, end=None: cube_scene(1, h, G, o, **({"end": end} if end else {})),
         lambda X, t: cube_displacement(X, t, G),
         [1 / 8, 1 / 16, 1 / 32, 1 / 64, 1 / 128], [1 / 8, 1 / 16, 1 / 32], 1.0),
    Case("square", "E6 unit square (2D, G = 0.05, one period, rollers)",
         lambda h, o, end=None: cube_scene(2, h, G, o, **({"end": end} if end else {})),
         lambda X, t: cube_displacement(X, t, G),
         [1 / 4, 1 / 8, 1 / 16, 1 / 32], [1 / 4, 1 / 8, 1 / 16], 0.99),
    Case("vortex", "E7 generalized vortex (2D, t in [0, 1] s)",
         lambda h, o, end=None: with_grid_box(vortex_scene(h, o, **({"end": end} if end else {}))),
         vortex_displacement,
         [0.1, 0.05, 1 / 30], [0.1, 0.05], 1.0),
]

SHAPES = ["linear", "gimp", "cubic_bspline", "quadratic_bspline", "bernstein", "cpdi_r4"]
QUICK_SHAPES = ["linear", "cubic_bspline", "bernstein"]


def methods(quick: bool, shapes: list[str] | None = None) -> list[Options]:
    out = []
    for formulation in ("ulmpm", "tlmpm"):
        for shape in shapes or (QUICK_SHAPES if quick else SHAPES):
            for transfer in ("flip",) if quick else ("flip", "apic", "mls"):
                out.append(Options(formulation=formulation, shape=shape, transfer=transfer))
    return out


def label(o: Options) -> str:
    return f"{o.formulation} {o.shape} {o.transfer}"


def simulate(scene: dict, displacement, samples: int = 21) -> dict:
    """Step a scene directly (no output files) and sample the error norms at `samples`
    evenly spaced times, as the tests do from the result frames. The time is the CPU
    time of the steps alone (numba kernels are single-threaded), which on a shared
    machine is what an idle one would take as wall time."""
    scene = load_scene(scene)
    sim = ExplicitMPM(scene)
    steps = max(1, round(scene.time.end / scene.time.dt))
    dt = scene.time.end / steps
    p = sim.particles
    X = p.x.copy()
    errors = DisplacementErrors()
    errors.add(0.0, X, p.x, p.volume0, displacement(X, 0.0))
    sample = {round(k * steps / (samples - 1)) for k in range(1, samples)}
    cpu = 0.0
    try:
        for step in range(1, steps + 1):
            start = time.process_time()
            sim.advance(dt)
            cpu += time.process_time() - start
            if step in sample:
                sim.check_finite()
                errors.add(sim.time, X, p.x, p.volume0, displacement(X, sim.time))
    except Instability as error:
        return {"failed": str(error), "seconds": cpu}
    return {"e1": errors.e1, "e2": errors.e2, "seconds": cpu, "particles": p.count, "steps": steps,
            "rate": p.count * steps / cpu}


def measure(case: Case, options: Options, levels: list[float]) -> list[dict] | str:
    """One row per level, or the reason the method does not apply to the case."""
    options = replace(options, flip_ratio=case.flip_ratio)
    try:
        load_scene(case.build(levels[0], options))
    except SceneError as error:
        return str(error).splitlines()[0]
    simulate(case.build(levels[0], options, end=1e-9), case.displacement, samples=2)   # compile first
    return [{"h": h, **simulate(case.build(h, options), case.displacement)} for h in levels]


def table(case: Case, results: dict[str, list[dict] | str]) -> str:
    lines = [f"### {case.title}", "",
             "| method | h | e2 | e1 | order (e2) | time s | particles | particle-steps/s |",
             "|---|---|---|---|---|---|---|---|"]
    skipped = []
    for name, rows in results.items():
        if isinstance(rows, str):
            skipped.append(f"- {name}: {rows}")
            continue
        for i, r in enumerate(rows):
            if "failed" in r:
                lines.append(f"| {name} | {r['h']:.4g} | unstable: {r['failed']} | | | {r['seconds']:.2f} | | |")
                continue
            before = rows[i - 1] if i > 0 else {}
            order = f"{observed_orders([before['h'], r['h']], [before['e2'], r['e2']])[0]:.2f}" if "e2" in before else ""
            lines.append(f"| {name} | {r['h']:.4g} | {r['e2']:.3e} | {r['e1']:.3e} | {order} | "
                         f"{r['seconds']:.3g} | {r['particles']} | {r['rate']:.3g} |")
    if skipped:
        lines += ["", "Not run:", *skipped]
    return "\n".join(lines)


def plot(case: Case, results: dict, path: Path) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 5))
    for name, rows in results.items():
        if isinstance(rows, str):
            continue
        good = [r for r in rows if "e2" in r]
        if good:
            style = "-" if name.startswith("tlmpm") else "--"
            marker = "o" if name.endswith("flip") else "s"
            ax.loglog([r["seconds"] for r in good], [r["e2"] for r in good], style, marker=marker, label=name)
    ax.set_xlabel("time of the steps [s] (CPU, one thread)")
    ax.set_ylabel("error e2 (Appendix A.13)")
    ax.set_title(case.title)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="2-3 coarse levels, FLIP, linear/cubic/Bernstein")
    parser.add_argument("--cases", nargs="*", default=[c.name for c in CASES], help="segment square vortex")
    parser.add_argument("--no-plots", action="store_true")
    parser.add_argument("--shapes", nargs="*", help="only these shape functions (e.g. cpdi_r4 gimp)")
    args = parser.parse_args()
    started = time.perf_counter()
    images = ROOT / "docs" / "images"
    for case in (c for c in CASES if c.name in args.cases):
        levels = case.quick_levels if args.quick else case.levels
        results = {}
        for options in methods(args.quick, args.shapes):
            results[label(options)] = measure(case, options, levels)
            print(f"  {case.name}: {label(options)} done ({time.perf_counter() - started:.0f} s)",
                  file=sys.stderr, flush=True)
        print(table(case, results), "\n", flush=True)
        if not args.no_plots:
            plot(case, results, images / f"convergence_{case.name}.png")
    print(f"total {math.ceil(time.perf_counter() - started)} s", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
