"""Dam break (Karamelo 4.5) at about 12k and 50k particles: speed against error.

    python benchmarks/dam_break.py [--end T]
    python benchmarks/dam_break.py --only 50k --end 1.6; python benchmarks/dam_break.py --report

Runs examples/dam_break_2d.json (100 x 100 cells of 0.0161, 3 x 3 particles per
cell: 12 321 particles) and the same with the cell halved (200 x 200, 49 284
particles) to T = 3 of Karamelo's eq. 4.6, and reports wall time, steps and
particle-steps per second, and the surge front L(T) of both against Martin &
Moyce (1952) and Ritter's shallow-water line. The error proxy is the largest
difference between the two resolutions' fronts before the far wall. Writes
docs/images/dam_break_front.png and docs/images/dam_break_pressure.png (the
12k run coloured by the grid-smoothed pressure at T = 1.2), and prints the table of
docs/benchmarks.md "Dam break". The two resolutions run side by side, one
process each; each run's numbers are kept in out/dam_break/ so that a
resolution can be run on its own (--only) and the report made from both.
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "verification"))

from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from mpm_cases import Case  # noqa: E402
from test_dam_break import G, L0, MARTIN_MOYCE_T, MARTIN_MOYCE_Z, WALL, front_curve, ritter  # noqa: E402

from solver import run  # noqa: E402
from solver.preview import render_preview  # noqa: E402

IMAGES = ROOT / "docs" / "images"
OUT = ROOT / "out" / "dam_break"     # each run's numbers, so the two may run separately
RUNS = {"12k": 100, "50k": 200}      # cells per axis


def scene(cells: int, end_T: float, frames: int) -> dict:
    s = json.loads((ROOT / "examples" / "dam_break_2d.json").read_text())
    s["grid"]["cell_size"] = 1.61 / cells
    s["time"]["end"] = end_T / math.sqrt(G / L0)
    s["output"] = {"frames": frames, "fields": ["position", "velocity", "pressure", "pressure_smoothed"],
                   "energies": True, "preview": {"field": "pressure_smoothed"}}
    return s


def run_one(name: str, cells: int, end_T: float, frames: int) -> dict:
    """One resolution, timed, in its own process (the two run side by side on two cores)."""
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        run(scene(20, 0.05, 2), tmp / "warm")        # compile (or load the cache) outside the timing
        start = time.perf_counter()
        case = Case(run(scene(cells, end_T, frames), tmp / name))
        wall = time.perf_counter() - start
        r = case.result
        T, L = front_curve(case)
        s = case.series()
        drift = float(np.max(s["total_energy"] - s["external_work"] - s["boundary_work"]))
        if name == "12k":
            IMAGES.mkdir(parents=True, exist_ok=True)
            render_preview(r.result_path, int(np.argmin(np.abs(T - 1.2))), "pressure_smoothed",
                           IMAGES / "dam_break_pressure.png")
        return dict(cells=cells, particles=r.particles, steps=r.steps, wall=wall, status=r.status,
                    rate=r.particles * r.steps / wall, T=T.tolist(), L=L.tolist(), drift=drift,
                    work=float(s["external_work"].max()))


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--end", type=float, default=3.0, help="end, in Karamelo's T")
    parser.add_argument("--only", choices=list(RUNS), help="run one resolution (then --report)")
    parser.add_argument("--report", action="store_true", help="only the table and plot of the saved runs")
    args = parser.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    if not args.report:
        names = [args.only] if args.only else list(RUNS)
        frames = int(round(args.end * 10)) + 1           # every dT = 0.1
        with ProcessPoolExecutor(max_workers=len(names)) as pool:
            futures = {name: pool.submit(run_one, name, RUNS[name], args.end, frames) for name in names}
            for name, future in futures.items():
                (OUT / f"{name}.json").write_text(json.dumps(future.result()))
    results = {name: json.loads((OUT / f"{name}.json").read_text()) for name in RUNS if (OUT / f"{name}.json").exists()}
    for r in results.values():
        r["T"], r["L"] = np.array(r["T"]), np.array(r["L"])
    report(results)
    plot(results)
    return 0


def report(results: dict) -> None:
    print("| particles | cells | end T | steps | wall time (s) | particle-steps/s | max energy gain / gravity work | status |")
    print("|---|---|---|---|---|---|---|---|")
    for r in results.values():
        print(f"| {r['particles']} | {r['cells']} x {r['cells']} | {r['T'][-1]:.2f} | {r['steps']} | {r['wall']:.1f} | "
              f"{r['rate']:.3g} | {max(r['drift'], 0.0) / r['work']:.2g} | {r['status']} |")
    if len(results) == 2:
        a, b = results["12k"], results["50k"]
        n = min(len(a["T"]), len(b["T"]))
        before = (a["L"][:n] < WALL - 0.05) & (b["L"][:n] < WALL - 0.05)
        print(f"\nlargest |L_50k - L_12k| before the wall: {np.max(np.abs(a['L'][:n] - b['L'][:n])[before]):.3f}")
    print("\nT, " + ", ".join(f"L_{n}" for n in results))
    longest = max(results.values(), key=lambda r: len(r["T"]))
    for i, t in enumerate(longest["T"]):
        print(f"{t:.2f}, " + ", ".join(f"{r['L'][i]:.3f}" if i < len(r["L"]) else "" for r in results.values()))


def plot(results: dict) -> None:
    figure = Figure(figsize=(7.0, 4.5), dpi=100)
    FigureCanvasAgg(figure)
    ax = figure.add_subplot()
    T = np.linspace(0, 3, 100)
    ax.plot(T, np.minimum(ritter(T), WALL), "k--", lw=1, label="Ritter (shallow water): 1 + 2T")
    ax.plot(MARTIN_MOYCE_T / math.sqrt(2), MARTIN_MOYCE_Z, "ks", ms=4, label="Martin & Moyce (1952), n² = 1")
    for name, r in results.items():
        ax.plot(r["T"], r["L"], "o-", ms=3, label=f"MPM {r['particles']} particles")
    ax.axhline(WALL, color="grey", lw=0.8)
    ax.set_xlim(0, 3)
    ax.set_ylim(0.9, 3.2)
    ax.set_xlabel("T = t sqrt(g h0) / l0")
    ax.set_ylabel("L = l / l0")
    ax.set_title("Dam break: surge front")
    ax.legend(loc="upper left", fontsize=8)
    ax.grid(alpha=0.3)
    figure.savefig(IMAGES / "dam_break_front.png", dpi=100)


if __name__ == "__main__":
    raise SystemExit(main())
