"""Geomaterials (issue 20): cost of Drucker-Prager and Mohr-Coulomb against J2, and the
verification figures -> docs/benchmarks.md, docs/images/geo_*.png.

    python benchmarks/geomaterials.py [--repeats N] [--no-figures]

1. Cost per particle-step, side by side in one process: the tall granular column
   (examples/granular_collapse_tall_2d.json) is run for a while with Drucker-Prager,
   so that the particles carry a mix of elastic, yielding and apex states; then, on
   copies of that same state (L, stress), the stress update of each model (J2
   plasticity with a yield stress of the order of the column's stresses, Drucker-Prager,
   Mohr-Coulomb) is timed, interleaved, `repeats` times; and whole steps of the scene
   are timed with each material from the same start. Ratios to J2 with their spread.
2. Errors and wall times of the single-point, geostatic and absorbing cases (the
   functions of their tests).
3. Figures: the oedometer stress path (single material point), the strip footing's
   load-settlement curves, the column collapses' deposits against Lube et al. (2005).
"""
from __future__ import annotations

import argparse
import copy
import json
import math
import statistics
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "verification"))

from mpm_cases import Case  # noqa: E402
from solver import materials, run  # noqa: E402
from solver.results import read_frame, read_series  # noqa: E402
from solver.scene_checks import load_scene  # noqa: E402
from solver.stepper import ExplicitMPM  # noqa: E402

EXAMPLES = ROOT / "examples"
IMAGES = ROOT / "docs" / "images"
SAND = json.loads((EXAMPLES / "granular_collapse_tall_2d.json").read_text())["materials"]["sand"]
ELASTIC = {key: SAND[key] for key in ("density", "youngs_modulus", "poisson_ratio")}
MODELS = {
    "j2_plasticity": {**ELASTIC, "model": "j2_plasticity", "yield_stress": 1000.0},   # ~ the column's deviatoric stress
    "drucker_prager": SAND,
    "mohr_coulomb": {**{k: v for k, v in SAND.items() if k != "fit"}, "model": "mohr_coulomb"},
}


def scene_with(material: dict) -> dict:
    scene = json.loads((EXAMPLES / "granular_collapse_tall_2d.json").read_text())
    scene["materials"]["sand"] = material
    scene["bodies"][0]["initial_stress"]["k0"] = 1 - math.sin(math.radians(SAND["friction_angle"]))   # J2 has no phi
    return scene


def spread(values):
    return f"{statistics.median(values):.3g} ({min(values):.3g} .. {max(values):.3g})"


def update_costs(repeats: int):
    """ns per particle of each model's update_stress on the same mid-collapse state."""
    sim = ExplicitMPM(load_scene(scene_with(MODELS["drucker_prager"])))
    dt = sim.stable_time_step(0.5)
    while sim.time < 0.15:          # mid-collapse: yielding, elastic and apex particles
        sim.advance(dt)
    p = sim.particles
    states = np.bincount(p.extra["yield_state"].astype(int), minlength=5)
    tiles = 50        # 80000 particles: the parallel launch is a small share of a call
    L0, stress0 = np.tile(p.L, (tiles, 1, 1)), np.tile(p.stress, (tiles, 1, 1))
    count = L0.shape[0]
    solvers = {}
    for name, config in MODELS.items():
        schema = materials.REGISTRY[config["model"]].schema
        solvers[name] = materials.create(schema.model_validate(config), 2)
    fake = copy.copy(p)
    fake.extra = {name: np.zeros(count) for name in ("plastic_strain", "yield_state")}
    times = {name: [] for name in MODELS}
    for _ in range(repeats):
        for name, model in solvers.items():
            fake.L, fake.stress = L0.copy(), stress0.copy()
            model.update_stress(fake, slice(0, count), dt)       # warm (and compiled)
            fake.stress = stress0.copy()
            start = time.perf_counter()
            for _ in range(5):
                model.update_stress(fake, slice(0, count), dt)
            times[name].append((time.perf_counter() - start) / 5 / count * 1e9)
    return times, states, count


def step_costs(repeats: int, steps: int = 300):
    """s per particle-step of whole steps of the scene with each material, from the same start."""
    sims = {name: ExplicitMPM(load_scene(scene_with(config))) for name, config in MODELS.items()}
    dt = sims["drucker_prager"].stable_time_step(0.5)
    for sim in sims.values():
        sim.advance(dt)               # compile
    times = {name: [] for name in MODELS}
    for _ in range(repeats):
        for name, sim in sims.items():
            start = time.perf_counter()
            for _ in range(steps):
                sim.advance(dt)
            times[name].append((time.perf_counter() - start) / steps / sim.particles.count * 1e9)
    return times


def ratio_rows(times):
    base = times["j2_plasticity"]
    return {name: [t / b for t, b in zip(values, base)] for name, values in times.items()}


def timed(function, *args):
    start = time.perf_counter()
    value = function(*args)
    return value, time.perf_counter() - start


def triaxial_error(extra, compression):
    import test_geomaterials as tg
    from material_point import MaterialPoint
    p0 = 1e5
    point = MaterialPoint(tg.soil(extra), 3, stress=-p0 * np.eye(3))
    for _ in range(250):
        point.mixed_step(np.diag([0.0, 0.0, -0.05 if compression else 0.05]), 4e-3, held=(0, 1), target=-p0,
                         stiffness=2 * tg.K + 2 * tg.G / 3)
    return abs(point.stress[2, 2] / tg.axial_failure_stress(extra, p0, compression) - 1)


def surface_error(extra):
    import test_geomaterials as tg
    return max(abs(tg.phi_value(extra, after)) for _, after, _, _ in tg.random_plastic_steps(tg.soil(extra), 3)) / 1e5


def oedometer_error(model):
    """Largest deviation from nu / (1 - nu) (elastic, relative) and from the Rankine line
    (plastic, of the largest stress)."""
    import test_geomaterials as tg
    sv, sh, state = tg.oedometer(tg.soil({"model": model}), 3).T
    ka = (1 - math.sin(math.radians(tg.PHI))) / (1 + math.sin(math.radians(tg.PHI)))
    elastic, plastic = state == 0, state > 0
    e1 = np.abs(sh[elastic] / sv[elastic] / (tg.NU / (1 - tg.NU)) - 1).max()
    e2 = np.abs(sh[plastic] - (ka * sv[plastic] - 2 * tg.C * math.sqrt(ka))).max() / sv.max()
    return max(e1, e2)


def verification_rows():
    """(case, error, wall time) of the single-point, geostatic and absorbing cases."""
    import test_absorbing as ta
    import test_geomaterials as tg
    import test_geostatic as tgs
    rows = []
    for extra in tg.MODELS:
        name = extra.get("fit", extra["model"])
        for compression in (True, False):
            error, wall = timed(triaxial_error, extra, compression)
            rows.append((f"triaxial {'compression' if compression else 'extension'}, {name}: axial stress at "
                         "failure, relative", error, wall))
        error, wall = timed(surface_error, extra)
        rows.append((f"{name}: max abs(Phi) / 100 kPa after 300 random plastic steps", error, wall))
    for model in ("mohr_coulomb", "drucker_prager"):
        error, wall = timed(oedometer_error, model)
        rows.append((f"oedometer, {model}: elastic K0 and Rankine line", error, wall))
    for height in (1.0, 0.975):
        (_, fastest), wall = timed(tgs.settle, tgs.column(height, {"type": "geostatic"}))
        rows.append((f"geostatic column, top at {height} m: max speed / sqrt(g H)", fastest / math.sqrt(tgs.G * height),
                     wall))
    (_, shocked), wall = timed(tgs.settle, tgs.column(1.0, None))
    rows.append(("the same column stress-free (gravity shock): max speed / sqrt(g H)", shocked / math.sqrt(tgs.G),
                 wall))
    for label, scene, speed in (("1D bar, absorbing ends", ta.bar(("x-", "x+")), ta.C_P),
                                ("1D bar, free ends", ta.bar(()), ta.C_P),
                                ("2D strip, P wave", ta.bar(("x-", "x+"), 2, "p"), ta.C_P),
                                ("2D strip, S wave", ta.bar(("x-", "x+"), 2, "s"), ta.C_S)):
        (left, _), wall = timed(ta.energy_left, scene, speed)
        rows.append((f"{label}: energy left / initial", left, wall))
    import test_cam_clay as tcc
    for cfl in (0.5, 0.25):
        (error, _), wall = timed(tcc.sloshing_energy_error, cfl)
        rows.append((f"Cam-Clay sloshing box, cfl {cfl}: largest energy error / initial kinetic energy", error, wall))
    return rows


def oedometer_figure(plt):
    import test_geomaterials as tg
    fig, ax = plt.subplots(figsize=(5, 4))
    ka = (1 - math.sin(math.radians(tg.PHI))) / (1 + math.sin(math.radians(tg.PHI)))
    for model, marker in (("mohr_coulomb", "o"), ("drucker_prager", "x")):
        sv, sh, state = tg.oedometer(tg.soil({"model": model}), 3).T
        ax.plot(sv[::25] / 1e3, sh[::25] / 1e3, marker, mfc="none", label=f"{model} (3D material point)")
    sv = np.linspace(0, sv.max(), 100)
    onset = 2 * tg.C * math.sqrt(ka) / (ka - tg.NU / (1 - tg.NU))
    ax.plot(sv / 1e3, tg.NU / (1 - tg.NU) * sv / 1e3, "k:", label="elastic: nu / (1 - nu)")
    ax.plot(sv / 1e3, (ka * sv - 2 * tg.C * math.sqrt(ka)) / 1e3, "k--", label="Rankine active line")
    ax.axvline(onset / 1e3, color="grey", lw=0.5)
    ax.set_xlabel("sigma_v (kPa, compression)")
    ax.set_ylabel("sigma_h (kPa)")
    ax.legend(fontsize=7)
    ax.set_title(f"Oedometer: phi = {tg.PHI:g}, c = {tg.C / 1e3:g} kPa, nu = {tg.NU:g}", fontsize=9)
    fig.tight_layout()
    fig.savefig(IMAGES / "geo_oedometer.png", dpi=110)


def footing_figure(plt, folder: Path):
    import test_strip_footing as tf
    fig, ax = plt.subplots(figsize=(5, 4))
    rows = []
    for cell, end, ppc, label in ((None, None, 1, "h = B/8, 1 particle per cell"),
                                  (0.03125, 0.6, 1, "h = B/16, 1 particle per cell"),
                                  (None, None, 2, "h = B/8, 2x2 particles per cell (locks)")):
        scene = tf.footing_scene(cell, end)
        for body in scene["bodies"]:
            body["particles_per_cell"] = ppc
        start = time.perf_counter()
        result = run(scene, folder / f"footing_{cell}_{ppc}")
        wall = time.perf_counter() - start
        series = read_series(result.result_path)
        q = np.asarray(series["reaction_footing_y"]) / tf.HALF_WIDTH / tf.COHESION
        settlement = 0.01 * np.asarray(series["time"]) / (2 * tf.HALF_WIDTH)
        ax.plot(100 * settlement, q, label=label)
        rows.append((label, q.max(), q.max() / tf.PRANDTL - 1, wall, result.steps, result.particles))
    ax.axhline(tf.PRANDTL, color="k", ls="--", label="Prandtl 2 + pi")
    ax.set_xlabel("settlement / B (%)")
    ax.set_ylabel("q / c")
    ax.set_ylim(0, 7)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(IMAGES / "geo_footing.png", dpi=110)
    return rows


def collapse_figure(plt, folder: Path):
    import test_granular_collapse as tc
    fig, axes = plt.subplots(2, 1, figsize=(6, 5))
    rows = []
    for ax, (name, aspect) in zip(axes, (("granular_collapse_low_2d", 0.8), ("granular_collapse_tall_2d", 4.0))):
        scene = json.loads((EXAMPLES / f"{name}.json").read_text())
        start = time.perf_counter()
        result = run(scene, folder / name)
        wall = time.perf_counter() - start
        case = Case(result)
        runout, height, speed = tc.deposit(case, scene)
        width = scene["bodies"][0]["geometry"]["upper"][0]
        first, last = read_frame(result.result_path, 0)["fields"], read_frame(result.result_path, -1)["fields"]
        ax.plot(first["position"][:, 0] / width, first["position"][:, 1] / width, ",", color="0.7")
        ax.plot(last["position"][:, 0] / width, last["position"][:, 1] / width, ",", color="C0")
        lube = 1.2 * aspect if aspect < 1.8 else 1.9 * aspect ** (2 / 3)
        lube_height = aspect if aspect < 1.15 else aspect ** 0.4
        ax.axvline(1 + lube, color="k", ls="--", label="Lube et al. 2005 runout")
        ax.axhline(lube_height, color="k", ls=":", label="Lube et al. 2005 final height")
        ax.set_title(f"a = {aspect:g}", fontsize=9)
        ax.set_aspect("equal")
        ax.set_ylabel("y / L0")
        ax.legend(fontsize=6, loc="upper right")
        rows.append((name, aspect, runout, lube, height, lube_height, speed, wall, result.steps, result.particles))
    axes[-1].set_xlabel("x / L0")
    fig.tight_layout()
    fig.savefig(IMAGES / "geo_collapse.png", dpi=110)
    return rows


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--no-figures", action="store_true")
    args = parser.parse_args()
    print("| case | error | wall time (s) |\n|---|---|---|")
    for case, error, wall in verification_rows():
        print(f"| {case} | {error:.2g} | {wall:.2f} |")
    updates, states, count = update_costs(args.repeats)
    print(f"stress update, {count} particles (50 copies of the column mid-collapse ; yield states 0..4 of one copy: {states.tolist()}), ns per particle,"
          f" median (min .. max) of {args.repeats}")
    ratios = ratio_rows(updates)
    print("| model | ns / particle | ratio to J2 |\n|---|---|---|")
    for name in MODELS:
        print(f"| {name} | {spread(updates[name])} | {spread(ratios[name])} |")
    steps = step_costs(args.repeats)
    ratios = ratio_rows(steps)
    print("\nwhole step, ns per particle-step\n| model | ns / particle-step | ratio to J2 |\n|---|---|---|")
    for name in MODELS:
        print(f"| {name} | {spread(steps[name])} | {spread(ratios[name])} |")
    if args.no_figures:
        return 0
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    oedometer_figure(plt)
    with tempfile.TemporaryDirectory() as tmp:
        for row in footing_figure(plt, Path(tmp)):
            print("footing | {} | q/c = {:.3f} | error {:+.1%} | {:.1f} s | {} steps | {} particles".format(*row))
        for row in collapse_figure(plt, Path(tmp)):
            print("collapse | {} a={} | runout {:.3f} vs {:.3f} | height {:.3f} vs {:.3f} | v {:.2g} | {:.1f} s "
                  "| {} steps | {} particles".format(*row))
    return 0


if __name__ == "__main__":
    sys.exit(main())
