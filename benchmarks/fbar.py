"""F-bar: the numbers of docs/benchmarks.md, section "F-bar and CPDI".

    python benchmarks/fbar.py

- The near-incompressible column of tests/verification/test_fbar_column.py
  (poisson_ratio 0.4999) with and without F-bar, for ULMPM (MUSL, USL, USF),
  TLMPM, GIMP, CPDI-R4, and neo-Hookean and J2 (elastic) material: sigma_yy error and the pressure checkerboard, / rho g H.
- The cost of F-bar: the same scene (the column, 4 x 4 particles per cell) stepped
  with and without it, alternately, 5 rounds of 200 steps; the ratio of the best
  times of each, and the spread of the ratios of the rounds.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "verification"))
sys.path.insert(0, str(ROOT / "benchmarks"))

from interleaved import round_times  # noqa: E402
from mpm_cases import Case  # noqa: E402
from test_fbar_column import column_measures, column_scene  # noqa: E402

from solver import run  # noqa: E402
from solver.scene_checks import load_scene  # noqa: E402
from solver.stepper import ExplicitMPM  # noqa: E402

ELASTIC = {"density": 1000.0, "youngs_modulus": 2.0e5, "poisson_ratio": 0.4999}
# name: (method keys, material or None for the test's linear_elastic)
VARIANTS = {"ulmpm musl linear": ({}, None), "ulmpm usl linear": ({"scheme": "usl"}, None),
            "ulmpm usf linear": ({"scheme": "usf"}, None), "tlmpm musl linear": ({"formulation": "tlmpm"}, None),
            "ulmpm musl gimp": ({"shape_function": "gimp"}, None),
            "ulmpm musl cpdi_r4": ({"shape_function": "cpdi_r4"}, None),
            "neo_hookean, ulmpm musl linear": ({}, {"model": "neo_hookean", **ELASTIC}),
            "j2_plasticity (yield 1e9), ulmpm musl linear": ({}, {"model": "j2_plasticity", "yield_stress": 1e9,
                                                                  **ELASTIC})}


def accuracy(out: Path) -> None:
    print("| method | F-bar | mean abs(syy + rho g d) | max | bottom row | checkerboard | wall s |")
    print("|---|---|---|---|---|---|---|")
    for name, (method, material) in VARIANTS.items():
        for fbar in (False, True):
            scene = column_scene(fbar)
            scene["method"].update(method)
            if material is not None:
                scene["materials"]["m"] = material
            start = time.perf_counter()
            m = column_measures(Case(run(scene, out / f"{name}-{fbar}".replace(" ", "_"))))
            wall = time.perf_counter() - start
            print(f"| {name} | {fbar} | {m['mean_syy']:.4f} | {m['max_syy']:.4f} | {m['bottom_syy']:.4f} "
                  f"| {m['checkerboard']:.4f} | {wall:.1f} |", flush=True)


def _stepper(fbar: bool) -> tuple[ExplicitMPM, float]:
    scene = column_scene(fbar)
    scene["bodies"][0]["particles_per_cell"] = 4
    sim = ExplicitMPM(load_scene(scene))
    dt = 0.5 * sim.stable_time_step(0.5)
    return sim, dt


def cost(rounds: int = 5, steps: int = 200) -> None:
    sims = {fbar: _stepper(fbar) for fbar in (False, True)}
    for sim, dt in sims.values():
        sim.advance(dt)   # compile
    times = round_times(sims, rounds, steps)
    best = {fbar: min(t) for fbar, t in times.items()}
    ratios = [a / b for a, b in zip(times[True], times[False])]
    n = sims[False][0].particles.count
    print(f"{n} particles: without {best[False] * n * 1e6:.0f} us/step, with {best[True] * n * 1e6:.0f} "
          f"us/step; ratio of the best {best[True] / best[False]:.3f}, rounds {min(ratios):.3f}-{max(ratios):.3f}")


if __name__ == "__main__":
    import tempfile
    with tempfile.TemporaryDirectory() as tmp:
        accuracy(Path(tmp))
    cost()
