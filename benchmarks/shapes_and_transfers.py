"""Shape functions and APIC: the numbers of docs/benchmarks.md, section
"Shape functions and transfers".

    python benchmarks/shapes_and_transfers.py

- E32: the largest deviation from partition of unity, linear reproduction and
  sum of gradients = 0 over 20 000 random 2D points (the cells at the grid ends
  included), and the cost of evaluating weights and gradients, as particles per
  second and relative to the linear hats (same process, best of 5).
- E23: the jump of a node's internal force as one particle crosses it
  (delta = 1e-3 h either side), relative to the linear jump 2 V sigma / h.
- APIC: the spinning elastic disk of tests/verification/test_apic.py (208
  particles, 10 revolutions): relative change of angular momentum and wall time
  for APIC, FLIP-0.99 and PIC with each C1 shape function.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "verification"))
sys.path.insert(0, str(ROOT / "tests" / "unit"))

from test_apic import angular_momentum_change  # noqa: E402
from test_cell_crossing import V, SIGMA, H, force_change_across_node_4  # noqa: E402
from test_shape_functions import evaluate, make_grid  # noqa: E402

SHAPES = ["linear", "gimp", "cpgimp", "quadratic_bspline", "cubic_bspline", "bernstein"]
MARGIN = {"quadratic_bspline": 0.5}


def property_errors(name: str, n: int = 20000) -> tuple[float, float, float, float]:
    grid = make_grid(2, cells=32, h=1.0 / 32)
    rng = np.random.default_rng(0)
    margin = MARGIN.get(name, 0.25 if "gimp" in name else 0.0)
    x = grid.lower + rng.uniform(margin, grid.cells - margin, size=(n, 2)) * grid.h
    evaluate(name, x[:10], grid)                                  # compile outside the timing
    best = min(_timed(lambda: evaluate(name, x, grid)) for _ in range(5))
    _, s = evaluate(name, x, grid)
    nodes = grid.node_positions()[s.idx]
    pu = np.abs(s.w.sum(axis=1) - 1).max()
    reproduction = np.abs(np.einsum("pk,pka->pa", s.w, nodes) - x).max() / grid.h.min()
    gradients = np.abs(s.dw.sum(axis=1)).max() * grid.h.min()
    return pu, reproduction, gradients, n / best


def _timed(f) -> float:
    start = time.perf_counter()
    f()
    return time.perf_counter() - start


def main() -> int:
    print("| shape function | max abs(sum w - 1) | max abs(sum w x_I - x) / h | max abs(sum grad w) h "
          "| weights, particles/s (2D) | cost vs linear |")
    print("|---|---|---|---|---|---|")
    rows = {name: property_errors(name) for name in SHAPES}
    for name, (pu, rep, grad, rate) in rows.items():
        print(f"| {name} | {pu:.1e} | {rep:.1e} | {grad:.1e} | {rate:.3g} | {rows['linear'][3] / rate:.2f} |")

    print("\n| shape function | force jump across a node (delta = 1e-3 h) / (2 V sigma / h) |")
    print("|---|---|")
    for name in ["linear", "bernstein", "gimp", "quadratic_bspline", "cubic_bspline"]:
        jump = np.abs(force_change_across_node_4(name, 1e-3)).max()
        print(f"| {name} | {jump / (2 * V * SIGMA / H):.2e} |")

    print("\n| shape function | transfer | angular momentum change, 10 revolutions | wall time (s) | steps |")
    print("|---|---|---|---|---|")
    angular_momentum_change("apic", "quadratic_bspline")          # compile once
    for name in ["quadratic_bspline", "cubic_bspline", "gimp", "cpgimp"]:
        for transfer in ["apic", "flip", "pic"]:
            start = time.perf_counter()
            change, sim = angular_momentum_change(transfer, name)
            wall = time.perf_counter() - start
            label = "FLIP-0.99" if transfer == "flip" else transfer.upper()
            print(f"| {name} | {label} | {change:+.2e} | {wall:.2f} | {sim.step_count} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
