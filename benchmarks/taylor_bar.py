"""Taylor bar (E8, [R] 6.3.1): final shape against the experiment at several resolutions.

    python benchmarks/taylor_bar.py [--3d]

Runs the axisymmetric Taylor bar of tests/verification/taylor_bar.py at cells of
0.4 and 0.2 mm (2 x 2 particles per cell) with linear hat functions and with
cubic B-splines, with linear hats and no rate term (C = 0, the review authors' own
input) at 0.4, 0.2 and 0.1 mm, the same onto an anvil with Coulomb friction 0.2 at 0.4,
0.2 and 0.1 mm and with 0.1 and 0.3 at 0.2 mm, in axisymmetric TLMPM (linear, one
particle per cell) at 0.4 and 0.2 mm; with --3d the 3D quarter bar at 0.8 and 0.3 mm
(2 x 2 x 2, ULMPM), the quarter without the rate term on the rough anvil at 0.8 and 0.4
mm, and examples/taylor_bar_3d_tlmpm.json (the review's TLMPM: linear, one particle
per cell) at cells of 0.508 and 0.254 mm. It prints the "Taylor bar" table of docs/benchmarks.md:
length, impact-face diameter and bulge, the error measure of [R] eq. 6.19, steps,
particles and wall time, under the experiment and [R] Table 6.
"""
from __future__ import annotations

import json
import math
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "verification"))

from mpm_cases import Case  # noqa: E402
from taylor_bar import EXPERIMENT, L0, R0, REVIEW, error_measure, measure, rough_anvil_scene, taylor_scene  # noqa: E402

from solver import run  # noqa: E402


def ulmpm(dim: int, cell: float, ppc: int, shape: str) -> tuple[str, dict, float]:
    scene = taylor_scene(cell, ppc, dim, frames=2)
    scene["method"]["shape_function"] = shape
    label = "axisymmetric" if dim == 2 else "3D quarter"
    return f"ULMPM {label}, {shape}, cell {cell * 1e3:g} mm, {ppc}^{dim} ppc", scene, cell / ppc


def without_rate_term(cell: float) -> tuple[str, dict, float]:
    """The review authors' own input (data/karamelo's Taylor bar: `C = 0#0.013`): no rate term."""
    label, scene, spacing = ulmpm(2, cell, 2, "linear")
    scene["materials"]["copper"] = {**scene["materials"]["copper"], "C": 0.0}
    return f"{label}, C = 0", scene, spacing


def rough_anvil(cell: float, friction: float, dim: int = 2) -> tuple[str, dict, float]:
    """Without the rate term, onto an anvil with Coulomb friction (tests/verification/taylor_bar.py)."""
    label = "axisymmetric" if dim == 2 else "3D quarter"
    return (f"ULMPM {label}, linear, cell {cell * 1e3:g} mm, 2^{dim} ppc, C = 0, anvil friction {friction:g}",
            rough_anvil_scene(cell, friction, dimension=dim), cell / 2)


def tlmpm_axisymmetric(cell: float) -> tuple[str, dict, float]:
    return f"TLMPM axisymmetric, linear, cell {cell * 1e3:g} mm, 1 ppc", \
        taylor_scene(cell, 1, 2, frames=2, formulation="tlmpm"), cell


def tlmpm_3d(cell: float) -> tuple[str, dict, float]:
    """examples/taylor_bar_3d_tlmpm.json at another cell size, the reference grid still just
    covering the bar (L0 / cell whole cells long: cell 0.254 mm seeds the 25.4 mm exactly,
    the example's 0.25 mm seeds 102 layers, 25.5 mm)."""
    scene = json.loads((ROOT / "examples" / "taylor_bar_3d_tlmpm.json").read_text())
    scene["output"]["frames"] = 2
    across = math.ceil(R0 / cell - 1e-9) * cell
    scene["grid"] = {"lower": [0.0, 0.0, 0.0], "upper": [across, round(L0 / cell) * cell, across], "cell_size": cell}
    return f"TLMPM 3D quarter, linear, cell {cell * 1e3:g} mm, 1 ppc", scene, cell


def main() -> int:
    runs = [ulmpm(2, cell, 2, shape) for shape in ("linear", "cubic_bspline") for cell in (0.4e-3, 0.2e-3)]
    runs += [without_rate_term(cell) for cell in (0.4e-3, 0.2e-3, 0.1e-3)]
    runs += [rough_anvil(cell, 0.2) for cell in (0.4e-3, 0.2e-3, 0.1e-3)]
    runs += [rough_anvil(0.2e-3, friction) for friction in (0.1, 0.3)]
    runs += [tlmpm_axisymmetric(0.4e-3), tlmpm_axisymmetric(0.2e-3)]
    if "--3d" in sys.argv:
        runs += [ulmpm(3, 0.8e-3, 2, "linear"), ulmpm(3, 0.3e-3, 2, "linear"),
                 rough_anvil(0.8e-3, 0.2, 3), rough_anvil(0.4e-3, 0.2, 3),
                 tlmpm_3d(0.508e-3), tlmpm_3d(0.254e-3)]
    print("| | length L (mm) | diameter D (mm) | bulge W (mm) | error eq. 6.19 | steps | particles | wall time (s) |")
    print("|---|---|---|---|---|---|---|---|")
    e = EXPERIMENT
    print(f"| experiment | {e['L'] * 1e3:.1f} | {e['D'] * 1e3:.1f} | {e['W'] * 1e3:.1f} | | | | |")
    for name, r in REVIEW.items():
        print(f"| [R] Table 6: {name} | {r['L'] * 1e3:.1f} | {r['D'] * 1e3:.1f} | {r['W'] * 1e3:.2f} | {r['error']} | | | |")
    with tempfile.TemporaryDirectory() as tmp:
        for shape in ("linear", "cubic_bspline"):    # compile outside the timings
            run(ulmpm(2, 0.8e-3, 1, shape)[1] | {"time": {"end": 2e-6}}, Path(tmp) / f"warm-{shape}")
        run(tlmpm_axisymmetric(0.8e-3)[1] | {"time": {"end": 2e-6}}, Path(tmp) / "warm-tlmpm")
        for i, (label, scene, spacing) in enumerate(runs):
            start = time.perf_counter()
            case = Case(run(scene, Path(tmp) / f"bar{i}"))
            wall = time.perf_counter() - start
            m = measure(case.frame(-1), spacing)
            print(f"| this project, {label} | {m['L'] * 1e3:.2f} | {m['D'] * 1e3:.2f} | {m['W'] * 1e3:.2f} | "
                  f"{error_measure(m):.3f} | {case.result.steps} | {case.result.particles} | {wall:.0f} |", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
