"""Sod's shock tube (E4) against the exact Riemann solution, with and without artificial viscosity.

    python benchmarks/sod.py

Runs examples/sod_shock_tube.json (400 cells, 3 particles per cell, cubic B-splines,
cfl 0.5, t = 0.2) with its artificial viscosity, without it, at smaller time steps
(cfl 0.1 and 0.025), with MLS instead of FLIP, with linear hats (the example
before issue 18) at cfl 0.5 and 0.025, and without the method and viscosity keys (the
ideal gas's defaults, issue 51; and those with linear hats named), and prints the table
of docs/benchmarks.md "Sod": L1 density error, the left plateau pressure, shock and contact positions (in cells) and the
wall time. Writes docs/images/sod.png: density, velocity and pressure at the
particles against the exact solution, and the pressure mapped to the grid and back.
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

from exact_riemann import SOD_RIGHT  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from mpm_cases import Case  # noqa: E402
from test_sod_shock_tube import EXACT, H, X0, defaults_scene, sod_scene  # noqa: E402

from solver import run  # noqa: E402

IMAGES = ROOT / "docs" / "images"


def measure(case) -> dict:
    frame = case.frame(-1)
    f = frame["fields"]
    order = np.argsort(f["position"][:, 0])
    x = f["position"][order, 0]
    rho, u, p = f["density"][order], f["velocity"][order, 0], f["pressure"][order]
    body = f["body"][order]
    t = frame["time"]
    waves = EXACT.wave_positions(t, X0)
    exact_rho, _, _ = EXACT.sample(x, t, X0)
    left = (x > waves["left_tail"] + 5 * H) & (x < waves["contact"] - 5 * H)
    contact = 0.5 * (x[body == 0].max() + x[body == 1].min())
    shock = x[p > 0.5 * (EXACT.p_star + SOD_RIGHT.p)].max()
    return dict(x=x, rho=rho, u=u, p=p, smooth=f["pressure_smoothed"][order], t=t,
                l1=float(np.mean(np.abs(rho - exact_rho))),
                plateau=float(np.median(p[left]) / EXACT.p_star - 1),
                shock=(shock - waves["right_head"]) / H, contact=(contact - waves["contact"]) / H)


def main() -> int:
    variants = [("with viscosity, cfl 0.5", True, 0.5, {}), ("without viscosity, cfl 0.5", False, 0.5, {}),
                ("with viscosity, cfl 0.1", True, 0.1, {}), ("with viscosity, cfl 0.025", True, 0.025, {}),
                ("MLS, cfl 0.5", True, 0.5, {"transfer": "mls"}), ("MLS, cfl 0.025", True, 0.025, {"transfer": "mls"}),
                ("linear hats, cfl 0.5", True, 0.5, {"shape_function": "linear"}),
                ("linear hats, cfl 0.025", True, 0.025, {"shape_function": "linear"})]
    # issue 51: the scene without its method and viscosity keys (the gas's defaults), and with linear hats named
    variants += [(f"defaults, cfl {cfl}", None, cfl, {}) for cfl in (0.5, 0.2, 0.1, 0.025)]
    variants += [(f"defaults but linear hats named, cfl {cfl}", None, cfl, {"shape_function": "linear"})
                 for cfl in (0.5, 0.2, 0.05)]
    # the particles' own volumes J V0 instead of the grid's density (solver/gas_density.py)
    own = {"density_from_grid": False}
    variants += [(f"defaults but linear hats named, own volumes, cfl {cfl}", None, cfl, {"shape_function": "linear"},
                  own) for cfl in (0.5, 0.2, 0.05)]
    variants += [("defaults, own volumes, cfl 0.5", None, 0.5, {}, own)]
    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for label, av, cfl, method, *gas in variants:
            scene = defaults_scene(cfl, method) if av is None else sod_scene(av)
            scene["materials"]["air"].update(*gas)
            scene["time"]["cfl"] = cfl
            scene["method"].update(method)
            scene["output"]["fields"].append("pressure_smoothed")
            start = time.perf_counter()
            case = Case(run(scene, tmp / label.replace(" ", "_").replace(",", "")))
            wall = time.perf_counter() - start
            rows[label] = dict(measure(case), wall=wall, steps=case.result.steps)
    print("| run | L1 density error | left plateau p / p* - 1 | shock (cells) | contact (cells) | steps | wall time (s) |")
    print("|---|---|---|---|---|---|---|")
    for label, r in rows.items():
        print(f"| {label} | {r['l1']:.4f} | {r['plateau']:+.3f} | {r['shock']:+.2f} | {r['contact']:+.2f} | "
              f"{r['steps']} | {r['wall']:.1f} |")
    plot(rows)
    print_vacuum_expansion()
    return 0


def print_vacuum_expansion() -> None:
    """A gas at rest in x < 0.5 expanding into a vacuum to t = 0.05 (a centred rarefaction, front
    at 0.5 + 2 c t / (gamma - 1)): the density from the grid, whose surface nodes are part
    empty, against the particles' own volumes (docs/scene.md, `density_from_grid`)."""
    gamma, c, end = 1.4, math.sqrt(1.4), 0.05
    print("\n| gas into a vacuum, t = 0.05 | L1 density error | front (exact 0.796) |\n|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for shape in ("linear", "cubic_bspline"):
            for from_grid in (True, False):
                scene = {"dimension": 1, "method": {"shape_function": shape},
                         "grid": {"lower": [0.0], "upper": [1.0], "cell_size": H},
                         "materials": {"air": {"model": "ideal_gas", "density_from_grid": from_grid}},
                         "bodies": [{"name": "gas", "material": "air", "particles_per_cell": 3,
                                     "initial_density": 1.0, "initial_pressure": 1.0,
                                     "geometry": {"type": "box", "lower": [0.0], "upper": [0.5]}}],
                         "boundary_conditions": [{"type": "wall", "face": "x-", "mode": "slip"}],
                         "time": {"end": end, "cfl": 0.5},
                         "output": {"frames": 2, "fields": ["position", "density"]}}
                frame = Case(run(scene, Path(tmp) / f"{shape}-{from_grid}")).frame(-1)
                order = np.argsort(frame["fields"]["position"][:, 0])
                x, rho = frame["fields"]["position"][order, 0], frame["fields"]["density"][order]
                xi = (x - X0) / frame["time"]
                sound = c - (gamma - 1) / 2 * (2 / (gamma + 1) * (c + xi))
                exact = np.where(xi < -c, 1.0, np.clip(sound / c, 0.0, None) ** (2 / (gamma - 1)))
                label = f"{shape}, {'density from the grid' if from_grid else 'own volumes'}"
                print(f"| {label} | {np.mean(np.abs(rho - exact)):.4f} | {x.max():.3f} |")


def plot(rows: dict) -> None:
    """Without and with the artificial viscosity (cubic B-splines), then linear hats with the
    particles' own volumes and with the density from the grid."""
    figure = Figure(figsize=(13.0, 10.5), dpi=90)
    FigureCanvasAgg(figure)
    xs = np.linspace(0, 1, 2001)
    with_av, without = rows["with viscosity, cfl 0.5"], rows["without viscosity, cfl 0.5"]
    own, grid = rows["defaults but linear hats named, own volumes, cfl 0.5"], rows["defaults but linear hats named, cfl 0.5"]
    exact = EXACT.sample(xs, with_av["t"], X0)
    names = ("density", "velocity", "pressure")
    panels = (((without, "particles", None), "cubic B-splines, without artificial viscosity"),
              ((with_av, "particles", None), "cubic B-splines, with artificial viscosity"),
              ((own, "own volumes J V0", grid), "linear hats: own volumes, density from the grid"))
    for column, (name, key, reference) in enumerate(zip(names, ("rho", "u", "p"), exact)):
        for row, ((r, label, other), title) in enumerate(panels):
            ax = figure.add_subplot(3, 3, 3 * row + column + 1)
            ax.plot(r["x"], r[key], ".", ms=2, label=label)
            if other is not None:
                ax.plot(other["x"], other[key], ".", ms=2, label="density from the grid")
            if key == "p" and row == 1:
                ax.plot(r["x"], r["smooth"], "-", lw=0.8, label="through the grid")
            ax.plot(xs, reference, "k-", lw=0.8, label="exact")
            ax.set_title(f"{name}, {title}", fontsize=9)
            ax.grid(alpha=0.3)
            if column == 2:
                ax.legend(fontsize=7)
    figure.suptitle(f"Sod's shock tube at t = {with_av['t']:.3g}: 400 cells, 3 particles per cell, MUSL, FLIP, "
                    "cfl 0.5")
    figure.tight_layout()
    IMAGES.mkdir(parents=True, exist_ok=True)
    figure.savefig(IMAGES / "sod.png", dpi=90)


if __name__ == "__main__":
    raise SystemExit(main())
