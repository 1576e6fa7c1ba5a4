"""Dam break (Karamelo 4.5) at about 12k and 50k particles: speed against error.

    python benchmarks/dam_break.py [--end T] [--only 12k|50k]

Runs examples/dam_break_2d.json (100 x 100 cells of 0.0161, 3 x 3 particles per
cell: 12 321 particles) and the same with the cell halved (200 x 200, 49 284
particles) to T = 3 of Karamelo's eq. 4.6, and reports wall time, steps and
particle-steps per second, and the surge front L(T) of both against Martin &
Moyce (1952) and Ritter's shallow-water line. The error proxy is the largest
difference between the two resolutions' fronts before the far wall. Writes
docs/images/dam_break_front.png and docs/images/dam_break_pressure.png (the
12k run coloured by pressure at T = 1.5), and prints the table of
docs/benchmarks.md "Dam break". The two resolutions run side by side, one
process each.
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


def scene(cells: int, end_T: float, frames: int) -> dict:
    s = json.loads((ROOT / "examples" / "dam_break_2d.json").read_text())
    s["grid"]["cell_size"] = 1.61 / cells
    s["time"]["end"] = end_T / math.sqrt(G / L0)
    s["output"] = {"frames": frames, "fields": ["position", "velocity", "pressure"],
                   "energies": True, "preview": {"field": "pressure"}}
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
            render_preview(r.result_path, int(np.argmin(np.abs(T - 1.5))), "pressure", IMAGES / "dam_break_pressure.png")
        return dict(cells=cells, particles=r.particles, steps=r.steps, wall=wall, status=r.status,
                    rate=r.particles * r.steps / wall, T=T, L=L, drift=drift, work=float(s["external_work"].max()))


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--end", type=float, default=3.0, help="end, in Karamelo's T")
    parser.add_argument("--only", choices=["12k", "50k"])
    args = parser.parse_args()
    runs = {"12k": 100, "50k": 200}
    if args.only:
        runs = {args.only: runs[args.only]}
    frames = int(round(args.end * 10)) + 1           # every dT = 0.1
    with ProcessPoolExecutor(max_workers=len(runs)) as pool:
        futures = {name: pool.submit(run_one, name, cells, args.end, frames) for name, cells in runs.items()}
        results = {name: future.result() for name, future in futures.items()}

    print("| particles | cells | steps | wall time (s) | particle-steps/s | max energy gain / gravity work | status |")
    print("|---|---|---|---|---|---|---|")
    for name, r in results.items():
        print(f"| {r['particles']} | {r['cells']} x {r['cells']} | {r['steps']} | {r['wall']:.1f} | "
              f"{r['rate']:.3g} | {max(r['drift'], 0.0) / r['work']:.2g} | {r['status']} |")
    if len(results) == 2:
        a, b = results["12k"], results["50k"]
        before = (a["L"] < WALL - 0.05) & (b["L"] < WALL - 0.05)
        print(f"\nlargest |L_50k - L_12k| before the wall: {np.max(np.abs(a['L'] - b['L'])[before]):.3f}")
    print("\nT, " + ", ".join(f"L_{n}" for n in results))
    first = next(iter(results.values()))
    for i, t in enumerate(first["T"]):
        print(f"{t:.2f}, " + ", ".join(f"{r['L'][i]:.3f}" for r in results.values()))
    plot(results)
    return 0


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
