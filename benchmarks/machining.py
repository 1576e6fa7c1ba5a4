"""Orthogonal machining (Karamelo 4.4, E18): run examples/machining_2d.json and draw its figures.

    python benchmarks/machining.py                      # the example: 320 x 80 cells, 0.15 mm of cut
    python benchmarks/machining.py --cells 160 40 --cut 0.3e-3
    python benchmarks/machining.py --cells 160 40 --report   # redraw from the kept result

Runs the example at the given grid (one particle per cell; the tool's travel `--cut`, in m),
timed as users run it (`solver.run`, one thread; the compiled kernels loaded first by a
short run outside the timing), and keeps the result in out/machining/<cells>/. Draws
docs/images/machining_chip.png (four snapshots coloured by the equivalent plastic strain,
the tool in grey), docs/images/machining_force.png (cutting and thrust force per unit
width against the tool's travel, with Merchant's frictionless band and the thrust a
frictionless rake face gives), docs/images/machining_preview.png (the run's preview of the
last frame) and prints the line of docs/benchmarks.md: the plateau of the cutting force
against Merchant's estimate (tests/verification/machining.py).
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "verification"))

from machining import SPEED, chip_rise, cutting_forces, machining_scene, merchant, \
    plateau, tool_travel  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.patches import Polygon  # noqa: E402
from mpm_cases import Case  # noqa: E402

from solver import run  # noqa: E402
from solver.preview import render_preview  # noqa: E402
from solver.results import list_frames, read_frame, read_series  # noqa: E402

IMAGES = ROOT / "docs" / "images"
OUT = ROOT / "out" / "machining"
PLATEAU_FROM = 0.1e-3   # tool travel (m) after which the cutting force is averaged


def run_example(cells: tuple[int, int], cut: float | None, frames: int) -> dict:
    folder = OUT / f"{cells[0]}x{cells[1]}"
    run(machining_scene(16, 4, 2e-6, frames=2), OUT / "warm")   # compile or load the kernels outside the timing
    start = time.perf_counter()
    result = Case(run(machining_scene(*cells, cut, frames=frames), folder)).result
    wall = time.perf_counter() - start
    record = {"cells": list(cells), "particles": result.particles, "steps": result.steps, "wall": wall,
              "status": result.status, "result": str(result.result_path)}
    (folder / "run.json").write_text(json.dumps(record))
    return record


def kept_record(folder: Path) -> dict:
    """The kept run's record; for a run stopped before its end (no run.json), what its result
    file holds up to its last complete frame (no wall time)."""
    if (folder / "run.json").exists():
        return json.loads((folder / "run.json").read_text())
    path = folder / "result.h5"
    last = list_frames(path)[-1]
    nx, ny = (int(n) for n in folder.name.split("x"))
    return {"cells": [nx, ny], "particles": last["particles"], "steps": last["step"], "wall": float("nan"),
            "status": "stopped", "result": str(path)}


def report(record: dict, steel: dict) -> None:
    path = record["result"]
    series = read_series(path)
    band = merchant(steel)
    mean, spread = plateau(series, PLATEAU_FROM)
    fc, ft = cutting_forces(series)
    late = tool_travel(series) > PLATEAU_FROM
    last = read_frame(path, -1)
    nx, ny = record["cells"]
    print(f"| {nx} x {ny} | {record['particles']} | {record['steps']} | {record['wall']:.0f} | "
          f"{SPEED * last['time'] * 1e3:.2f} | {mean / 1e3:.0f} (sd {spread / 1e3:.0f}) | "
          f"{band['mean'] / 1e3:.0f} ({band['low'] / 1e3:.0f}-{band['high'] / 1e3:.0f}) | "
          f"{mean / band['mean'] - 1:+.0%} | {np.mean(ft[late]) / np.mean(fc[late]):.3f} ({band['thrust_ratio']:.3f}) | "
          f"{chip_rise(last, last['time']) * 1e6:.0f} | {record['status']} |")


def draw_snapshots(record: dict, scene: dict) -> None:
    path = record["result"]
    frames = list_frames(path)
    picks = [frames[i] for i in np.linspace(0, len(frames) - 1, 4).astype(int)]
    tool = np.array(scene["tools"][0]["geometry"]["vertices"])
    velocity = np.array(scene["tools"][0]["velocity"], dtype=float)
    figure = Figure(figsize=(9.0, 5.6), dpi=100)
    FigureCanvasAgg(figure)
    nx, ny = record["cells"]
    dot = 40.0 * (80.0 / ny) ** 2 / 16   # about a cell's area in points at this figure size
    for k, info in enumerate(picks):
        ax = figure.add_subplot(2, 2, k + 1)
        fields = read_frame(path, info["index"])["fields"]
        x = fields["position"] * 1e3
        dots = ax.scatter(x[:, 0], x[:, 1], c=fields["plastic_strain"], s=dot, vmin=0.0, vmax=2.0, cmap="viridis",
                          linewidths=0)
        ax.add_patch(Polygon((tool + velocity * info["time"]) * 1e3, closed=True, color="0.55"))
        ax.set_xlim(0.35, 1.15)
        ax.set_ylim(0.0, 0.6)
        ax.set_aspect("equal")
        ax.set_title(f"t = {info['time'] * 1e6:.1f} us, travel {SPEED * info['time'] * 1e3:.2f} mm", fontsize=9)
        ax.tick_params(labelsize=7)
    figure.colorbar(dots, ax=figure.axes, shrink=0.8, label="equivalent plastic strain (clipped at 2)")
    figure.suptitle(f"Machining, TLMPM {nx} x {ny} cells: chip formation (x, y in mm)", fontsize=10)
    figure.savefig(IMAGES / "machining_chip.png", dpi=100)


def draw_forces(record: dict, steel: dict) -> None:
    series = read_series(record["result"])
    band = merchant(steel)
    travel = tool_travel(series) * 1e3
    fc, ft = cutting_forces(series)
    figure = Figure(figsize=(7.0, 4.2), dpi=100)
    FigureCanvasAgg(figure)
    ax = figure.add_subplot()
    ax.axhspan(band["low"] / 1e3, band["high"] / 1e3, color="0.9", label="Merchant, flow stress A to fully hardened")
    ax.axhline(band["mean"] / 1e3, color="k", ls="--", lw=1, label="Merchant, mean flow stress")
    ax.plot(travel, fc / 1e3, lw=1, label="cutting force F_c (reaction_cutter_x)")
    ax.plot(travel, ft / 1e3, lw=1, label="thrust F_t (reaction_cutter_y)")
    ax.plot(travel, band["thrust_ratio"] * fc / 1e3, color="0.5", lw=0.8, ls=":", label="-tan(rake) F_c")
    ax.set_xlabel("tool travel (mm)")
    ax.set_ylabel("force per unit width (kN/m = N/mm)")
    ax.set_title(f"Machining, {record['cells'][0]} x {record['cells'][1]} cells: forces on the tool", fontsize=10)
    ax.legend(fontsize=7, loc="lower right")
    ax.grid(alpha=0.3)
    figure.savefig(IMAGES / "machining_force.png", dpi=100)


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--cells", type=int, nargs=2, default=(320, 80), metavar=("NX", "NY"))
    parser.add_argument("--cut", type=float, default=None, help="tool travel (m); default: the example's")
    parser.add_argument("--frames", type=int, default=21)
    parser.add_argument("--report", action="store_true", help="only the figures and the line of the kept run")
    args = parser.parse_args()
    cells = tuple(args.cells)
    folder = OUT / f"{cells[0]}x{cells[1]}"
    OUT.mkdir(parents=True, exist_ok=True)
    record = kept_record(folder) if args.report else run_example(cells, args.cut, args.frames)
    scene = machining_scene(*cells)
    steel = scene["materials"]["steel"]
    IMAGES.mkdir(parents=True, exist_ok=True)
    print("| cells | particles | steps | wall (s) | travel (mm) | F_c after 0.1 mm (kN/m) | Merchant (kN/m) | "
          "difference | F_t / F_c (frictionless rake) | chip rise (um) | status |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    report(record, steel)
    draw_snapshots(record, scene)
    draw_forces(record, steel)
    render_preview(record["result"], -1, "plastic_strain", IMAGES / "machining_preview.png")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
