"""What the PIC share of the FLIP blend costs in damping: energy lost per period of a free vibration.

    python benchmarks/flip_damping.py            # the bar (1D) and the beam (2D), flip_ratio 1, 0.99, 0.95, PIC

Two free vibrations with no physical damping, so every loss is numerical:

  bar    the E1 bar of examples/bar_vibration.json (review 6.1.1): axial mode 1, 16 cells, 2 particles a cell
  beam   a cantilever, 1 m x 0.1 m, 4 cells through the thickness (h = 0.025), clamped at x = 0.1, given
         the velocity of its first bending mode (v_y = v0 (s/L)^2 (3 - s/L) / 2, s the distance from the clamp)

The vibration's energy is the energy balance of the run (solver/energy.py: kinetic + strain, no work
done). Its period T is the exact one: 4 L / c for the bar; for the beam Euler-Bernoulli's first mode,
2 pi / 1.875^2 sqrt(rho A L^4 / (E' I)) with the plane-strain modulus E' = E / (1 - nu^2) (1.79 s).
The loss per period is 1 - (E(t_end) / E(0))^(T / t_end); the amplitude's is 1 - sqrt(1 - that).
"""
from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from solver import run  # noqa: E402
from solver.results import read_series  # noqa: E402


def bar(flip_ratio: float | None) -> dict:
    scene = json.loads((ROOT / "examples" / "bar_vibration.json").read_text())
    scene["method"] = _method(flip_ratio)
    scene["output"] = {"frames": 2, "fields": ["position"]}
    return scene


def beam(flip_ratio: float | None) -> dict:
    length, v0 = 1.0, 0.05
    s = f"min(max((x - 0.1) / {length}, 0), 1)"
    return {
        "dimension": 2, "method": _method(flip_ratio),
        "grid": {"lower": [0.0, 0.3], "upper": [1.2, 0.7], "cell_size": 0.025},
        "materials": {"m": {"model": "linear_elastic", "density": 1000, "youngs_modulus": 1e6, "poisson_ratio": 0.3}},
        "bodies": [{"name": "beam", "material": "m", "particles_per_cell": 2,
                    "geometry": {"type": "box", "lower": [0.1, 0.45], "upper": [1.1, 0.55]},
                    "initial_velocity": [0.0, f"{v0} * ({s})**2 * (3 - {s}) / 2"]}],
        "boundary_conditions": [{"type": "velocity", "where": {"type": "box", "lower": [0.0, 0.3],
                                                                "upper": [0.1, 0.7]}, "velocity": [0, 0]}],
        "time": {"end": 6.0, "cfl": 0.5}, "output": {"frames": 2, "fields": ["position"]},
    }


def _method(flip_ratio: float | None) -> dict:
    return {"transfer": "pic"} if flip_ratio is None else {"transfer": "flip", "flip_ratio": flip_ratio}


BAR_PERIOD = 4 * 25.0 / 10.0   # 4 L / c, c = sqrt(E / rho) = 10
BEAM_PERIOD = 2 * np.pi / 1.875**2 * np.sqrt(1000 * 0.1 * 1.0**4 / (1e6 / (1 - 0.3**2) * 0.1**3 / 12))


def loss_per_period(series: dict, period: float) -> float:
    """The energy a free vibration lost per period, as a fraction."""
    t, energy = series["time"], series["energy_balance"]
    return 1.0 - (energy[-1] / energy[0]) ** (period / t[-1])


def main() -> None:
    print(f"{'case':<6}{'transfer':>14}{'period':>9}{'energy lost/period':>20}{'amplitude lost/period':>23}")
    for name, make, period in (("bar", bar, BAR_PERIOD), ("beam", beam, BEAM_PERIOD)):
        for flip in (1.0, 0.99, 0.95, None):
            with tempfile.TemporaryDirectory() as tmp:
                series = read_series(run(make(flip), tmp).result_path)
            lost = loss_per_period(series, period)
            amplitude = 1.0 - np.sqrt(1.0 - lost)
            label = "pic" if flip is None else f"flip {flip:g}"
            print(f"{name:<6}{label:>14}{period:>9.3g}{100 * lost:>19.2f}%{100 * amplitude:>22.2f}%", flush=True)


if __name__ == "__main__":
    main()
