"""The MLS speed table and plot of docs/benchmarks.md from repeated throughput runs.

    for i in 1 2 3; do python benchmarks/throughput.py --frameworks-python PY --side-by-side-only \\
        --blocks 2:225:15 3:32:6 --json run_$i.json; done
    python benchmarks/mls_speed_plot.py run_*.json          # -> docs/images/mls_speed.png
    python benchmarks/mls_speed_plot.py --image out.png --machine "16-core Xeon, quiet" run_*.json

Each run has the five implementations side by side (benchmarks/throughput.py);
the table gives, per block and thread count, the median of the runs and their
range (min-max) for the rates and for the ratios taken within each run.
"""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

IMAGE = Path(__file__).resolve().parent.parent / "docs" / "images" / "mls_speed.png"
RATES = (("solver", "solver APIC"), ("mls", "solver MLS"), ("mls_unfolded", "MLS unfolded"), ("numba", "numba MLS"),
         ("taichi", "Taichi"), ("warp", "Warp (1 thread)"))
RATIOS = (("mls", "solver", "MLS / APIC", None), ("mls", "mls_unfolded", "MLS / unfolded", None),
          ("mls", "numba", "MLS / numba", 0.9), ("mls", "taichi", "MLS / Taichi", 2.0),
          ("mls", "warp", "MLS / Warp", 1.2))


def spread(values: list[float], scale: float = 1.0, digits: int = 2) -> str:
    v = np.array(values) / scale
    return f"{np.median(v):.{digits}f} ({v.min():.{digits}f}-{v.max():.{digits}f})"


def _key(row: dict) -> tuple:
    return row.get("case", f"{row['dimension']}D block"), row["particles"], row["threads"]


def main(args: list[str]) -> int:
    image, machine = IMAGE, "shared 2-core machine"
    while args[:1] in (["--image"], ["--machine"]):
        if args[0] == "--image":
            image = Path(args[1])
        else:
            machine = args[1]
        args = args[2:]
    runs = [json.loads(Path(p).read_text())["side_by_side"] for p in args]
    rates_of = [(k, title) for k, title in RATES if all(k in r for run in runs for r in run)]   # older runs: no unfolded
    ratios_of = [r for r in RATIOS if all(r[0] in x and r[1] in x for run in runs for x in run)]
    rows = {_key(r): [next(x for x in run if _key(x) == _key(r)) for run in runs] for r in runs[0]}
    print("| case | threads | " + " | ".join(t for _, t in rates_of) + " | " + " | ".join(t for *_, t, _ in ratios_of)
          + " |")
    print("|---" * (2 + len(rates_of) + len(ratios_of)) + "|")
    for (case, n, threads), rs in rows.items():
        rates = [spread([r[k] for r in rs], 1e6) for k, _ in rates_of]
        ratios = [spread([r[a] / r[b] for r in rs]) for a, b, _, _ in ratios_of]
        print(f"| {case}, {n:,} | {threads} | " + " | ".join(rates) + " | " + " | ".join(ratios) + " |")
    goals = [r for r in ratios_of if r[3] is not None   # (a framework left out of the runs: no panel)
             and not all(np.isnan(x[r[0]] / x[r[1]]) for run in runs for x in run)]
    figure = Figure(figsize=(10, 4.2))
    FigureCanvasAgg(figure)
    axes = np.atleast_1d(figure.subplots(1, len(goals), sharey=False))
    labels = [f"{case.replace(' block', '')}\n{threads} thr." for case, _, threads in rows]
    for ax, (a, b, title, goal) in zip(axes, goals):
        values = np.array([[r[a] / r[b] for r in rs] for rs in rows.values()])
        median = np.median(values, axis=1)
        ax.bar(range(len(rows)), median, color="tab:blue", alpha=0.7)
        ax.errorbar(range(len(rows)), median, yerr=[median - values.min(axis=1), values.max(axis=1) - median],
                    fmt="none", color="k", capsize=3)
        ax.axhline(goal, color="tab:red", linestyle="--", label=f"goal {goal}")
        ax.set_ylim(0.0, 1.12 * max(np.nanmax(values), goal))   # the goal's line inside the frame
        ax.axhline(1.0, color="0.5", linewidth=0.8)
        ax.set_xticks(range(len(rows)), labels, fontsize=8)
        ax.set_title(title)
        ax.legend(loc="upper right", fontsize=8)
    axes[0].set_ylabel("ratio of particle-steps/s (median, min-max of runs)")
    figure.suptitle(f"MLS-MPM, side by side ({len(runs)} runs, {machine})")
    figure.tight_layout()
    figure.savefig(image, dpi=110)
    print(f"wrote {image}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
