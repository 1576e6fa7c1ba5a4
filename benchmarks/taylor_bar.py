"""Taylor bar (E8, [R] 6.3.1): final shape against the experiment at several resolutions.

    python benchmarks/taylor_bar.py [--3d]

Runs the axisymmetric Taylor bar of tests/verification/taylor_bar.py at cells of
0.4 and 0.2 mm (2 x 2 particles per cell), and with --3d the 3D quarter bar at
0.8 mm (2 x 2 x 2), and prints the "Taylor bar" table of docs/benchmarks.md:
length, impact-face diameter and bulge, the error measure of [R] eq. 6.19, steps,
particles and wall time, under the experiment and [R] Table 6.
"""
from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "verification"))

from mpm_cases import Case  # noqa: E402
from taylor_bar import EXPERIMENT, REVIEW, error_measure, measure, taylor_scene  # noqa: E402

from solver import run  # noqa: E402

RUNS = [(2, 0.4e-3, 2), (2, 0.2e-3, 2)]


def main() -> int:
    runs = RUNS + ([(3, 0.8e-3, 2)] if "--3d" in sys.argv else [])
    print("| | length L (mm) | diameter D (mm) | bulge W (mm) | error eq. 6.19 | steps | particles | wall time (s) |")
    print("|---|---|---|---|---|---|---|---|")
    e = EXPERIMENT
    print(f"| experiment | {e['L'] * 1e3:.1f} | {e['D'] * 1e3:.1f} | {e['W'] * 1e3:.1f} | | | | |")
    for name, r in REVIEW.items():
        print(f"| [R] Table 6: {name} | {r['L'] * 1e3:.1f} | {r['D'] * 1e3:.1f} | {r['W'] * 1e3:.2f} | {r['error']} | | | |")
    with tempfile.TemporaryDirectory() as tmp:
        run(taylor_scene(0.8e-3, 1, 2, end=2e-6), Path(tmp) / "warm")    # compile outside the timings
        for dim, cell, ppc in runs:
            start = time.perf_counter()
            case = Case(run(taylor_scene(cell, ppc, dim, frames=2), Path(tmp) / f"bar{dim}{cell}"))
            wall = time.perf_counter() - start
            m = measure(case.frame(-1), cell / ppc)
            label = "axisymmetric" if dim == 2 else "3D quarter"
            print(f"| this project, ULMPM {label}, cell {cell * 1e3:g} mm, {ppc}^{dim} ppc | {m['L'] * 1e3:.2f} | "
                  f"{m['D'] * 1e3:.2f} | {m['W'] * 1e3:.2f} | {error_measure(m):.3f} | {case.result.steps} | "
                  f"{case.result.particles} | {wall:.0f} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
