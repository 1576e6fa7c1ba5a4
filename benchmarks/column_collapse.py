"""Granular column collapse across aspect ratios (issue 51) -> docs/benchmarks.md, the
"Column collapse" table, and docs/images/collapse_runout.png.

    python benchmarks/column_collapse.py [--cells 10 20] [--aspects 0.5 1 2 3 5 8]

Columns of the examples' sand (phi = 33 degrees, no cohesion, no dilation) of width L0 =
0.1 m and aspect ratio a = H / L0, Drucker-Prager with the plane-strain fit and
Mohr-Coulomb, h = L0 / cells, run to 5 sqrt(H / g) (tests/verification/test_granular_collapse.py,
`column_scene`). Runout (L_inf - L0) / L0 and final height H_inf / L0 of the deposit (a
particle thrown off the flow, with no other within two lattice spacings, is not in it)
against Lube et al. (2005) and Lajeunesse et al. (2005). A run that stops early is listed
with its reason.
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "verification"))

import test_granular_collapse as tc  # noqa: E402
from mpm_cases import Case  # noqa: E402

from solver import run  # noqa: E402

MODELS = ("drucker_prager", "mohr_coulomb")
IMAGES = ROOT / "docs" / "images"


def collapse(aspect: float, model: str, cells: int, folder: Path) -> dict:
    """One run: its deposit, or why it stopped."""
    scene = tc.column_scene(aspect, model, cells)
    start = time.perf_counter()
    result = run(scene, folder / f"{model}_{aspect:g}_{cells}")
    row = {"aspect": aspect, "model": model, "cells": cells, "steps": result.steps,
           "particles": result.particles, "wall": time.perf_counter() - start}
    if result.status != "complete":
        return {**row, "stopped": result.message}
    runout, height, speed = tc.deposit(Case(result), scene)
    return {**row, "runout": runout, "height": height, "speed": speed}


def cell(row: dict) -> str:
    if "stopped" in row:
        return "stopped"
    low, high = tc.law_runout(row["aspect"])
    error = min(row["runout"] / low - 1, 0) + max(row["runout"] / high - 1, 0)
    return f"{row['runout']:.2f} ({'between' if error == 0 and low < high else f'{error:+.0%}'}); {row['height']:.2f}"


def span(bounds: tuple[float, float]) -> str:
    return f"{bounds[0]:.2f}" if bounds[0] == bounds[1] else f"{bounds[0]:.2f}-{bounds[1]:.2f}"


def table(rows: list[dict], cells: list[int]) -> None:
    header = " | ".join(f"{model} h = L0/{n}" for n in cells for model in MODELS)
    print(f"| a | Lube: runout; height | Lajeunesse runout | {header} | wall (s) |")
    print("|---" * (4 + 2 * len(cells)) + "|")
    for aspect in sorted({row["aspect"] for row in rows}):
        mine = [next(r for r in rows if r["aspect"] == aspect and r["model"] == model and r["cells"] == n)
                for n in cells for model in MODELS]
        lube_height = aspect if aspect < 1.15 else aspect ** 0.4
        walls = " / ".join(f"{r['wall']:.1f}" for r in mine)
        print(f"| {aspect:g} | {span(tc.law_runout(aspect))}; {lube_height:.2f} | "
              f"{span(tc.law_runout(aspect, tc.LAJEUNESSE))} | {' | '.join(cell(r) for r in mine)} | {walls} |")
    for row in rows:
        if "stopped" in row:
            print(f"{row['model']} a = {row['aspect']:g}, h = L0/{row['cells']}: {row['stopped']}")


def figure(rows: list[dict]) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np
    fig, ax = plt.subplots(figsize=(6, 4))
    a = np.geomspace(0.4, 10, 200)
    for (linear, power, first, second), name, style in ((tc.LUBE, "Lube et al. 2005", "k--"),
                                                        (tc.LAJEUNESSE, "Lajeunesse et al. 2005", "k:")):
        low, high = a[a <= second], a[a >= first]   # each branch over its range (both between the breaks)
        ax.plot(low, linear * low, style, label=name)
        ax.plot(high, power * high ** (2 / 3), style)
    for (model, n), marker in zip([(m, n) for n in sorted({r["cells"] for r in rows}) for m in MODELS], "os^v"):
        done = [r for r in rows if r["model"] == model and r["cells"] == n and "runout" in r]
        ax.plot([r["aspect"] for r in done], [r["runout"] for r in done], marker, mfc="none",
                label=f"{model}, h = L0/{n}")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("aspect ratio a = H / L0")
    ax.set_ylabel("runout (L_inf - L0) / L0")
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(IMAGES / "collapse_runout.png", dpi=110)


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--cells", type=int, nargs="+", default=[10, 20])
    parser.add_argument("--aspects", type=float, nargs="+", default=[0.5, 1, 2, 3, 5, 8])
    parser.add_argument("--no-figure", action="store_true")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        rows = [collapse(aspect, model, n, Path(tmp)) for n in args.cells for model in MODELS
                for aspect in args.aspects]
    table(rows, args.cells)
    if not args.no_figure:
        figure(rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
