"""Error and wall time of the verification cases of the solver core.

    python benchmarks/verification.py

Runs the scenes of tests/verification (the same builders) and prints, for each
case, the error against its reference and the wall time of the run: the
"Verification" table of docs/benchmarks.md, and the E1 plot
docs/images/bar_vibration.png (centre-of-mass velocity against the exact one).
"""
from __future__ import annotations

import math
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "verification"))

from mpm_cases import Case, centre_of_mass_velocity  # noqa: E402
from test_bar_vibration import L, V0, bar_scene, vcm_error  # noqa: E402
from test_two_disks import two_disks  # noqa: E402

from solver import run  # noqa: E402


def timed(scene, folder):
    start = time.perf_counter()
    case = Case(run(scene, folder))
    return case, time.perf_counter() - start


def main() -> int:
    rows = []
    curves = {}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        run(bar_scene(1, 13, 1, periods=0.1)[0], tmp / "warm")     # compile once, outside the timings
        for cells, ppc, transfer in [(13, 1, "flip"), (16, 2, "flip"), (26, 1, "flip"), (52, 1, "flip"),
                                     (16, 2, "pic")]:
            scene, beta, omega = bar_scene(1, cells, ppc, transfer=transfer)
            case, wall = timed(scene, tmp / f"bar{cells}{ppc}{transfer}")
            rows.append((f"E1 bar mode 1, {cells} cells x {ppc} ppc, MUSL {transfer.upper()}",
                         "max abs(v_cm - exact) / amplitude, 2 periods", vcm_error(case, beta, omega), wall,
                         case.result.steps, case.result.particles))
            if (cells, ppc) == (16, 2):
                frames = case.frames()
                curves[transfer] = ([f["time"] for f in frames], [centre_of_mass_velocity(f)[0] for f in frames])
                curves["omega"], curves["beta"] = omega, beta
        for scheme in ("usl", "musl"):
            scene, _, _ = bar_scene(10, 50, 1, scheme=scheme, periods=4.0, frames=5)
            case, wall = timed(scene, tmp / f"mode10{scheme}")
            s = case.series()
            rows.append((f"E1 bar mode 10, 50 cells x 1 ppc, {scheme.upper()} FLIP", "abs(E(end) - E(0)) / E(0)",
                         abs(s["total_energy"][-1] - s["total_energy"][0]) / s["total_energy"][0], wall,
                         case.result.steps, case.result.particles))
        for model in ("linear_elastic", "neo_hookean"):
            scene = two_disks()
            scene["materials"]["rubber"]["model"] = model
            case, wall = timed(scene, tmp / f"disks{model}")
            s = case.series()
            drift = np.abs(s["total_energy"] - s["total_energy"][0]) / s["total_energy"][0]
            rows.append((f"E2 two disks, {model}, MUSL FLIP", "max abs(E(t) - E(0)) / E(0)", drift.max(), wall,
                         case.result.steps, case.result.particles))
            rows.append((f"E2 two disks, {model}, MUSL FLIP", "abs(E(3.5) - E(0)) / E(0)", drift[-1], wall,
                         case.result.steps, case.result.particles))

    print(f"| case | error measure | error | wall time (s) | steps | particles |")
    print("|---|---|---|---|---|---|")
    for name, measure, error, wall, steps, particles in rows:
        print(f"| {name} | {measure} | {error:.3g} | {wall:.2f} | {steps} | {particles} |")
    _plot(curves, ROOT / "docs" / "images" / "bar_vibration.png")
    return 0


def _plot(curves, path: Path) -> None:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(7, 3.5))
    FigureCanvasAgg(fig)
    ax = fig.add_subplot()
    t = np.linspace(0, max(curves["flip"][0]), 400)
    ax.plot(t, V0 / (curves["beta"] * L) * np.cos(curves["omega"] * t), "k-", lw=1, label="exact")
    ax.plot(*curves["flip"], "o", ms=3, label="MUSL FLIP")
    ax.plot(*curves["pic"], "s", ms=3, label="MUSL PIC")
    ax.set_xlabel("t")
    ax.set_ylabel("centre-of-mass velocity")
    ax.set_title("E1: bar, mode 1, 16 cells x 2 particles")
    ax.legend(loc="lower left", fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    print(f"plot: {path.relative_to(ROOT)}")


if __name__ == "__main__":
    sys.exit(main())
