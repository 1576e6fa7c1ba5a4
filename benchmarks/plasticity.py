"""Error and wall time of the plasticity verification cases, and the copper bar example.

    python benchmarks/plasticity.py

Runs the single-material-point paths of tests/verification/test_plasticity.py
(the same functions) and prints each error against its closed form with the wall
time of the path, then runs examples/copper_bar_impact_2d.json and prints its
wall time, steps and final shape: the "Plasticity" tables of docs/benchmarks.md.
"""
from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "verification"))

import test_plasticity as tp  # noqa: E402

from solver import run  # noqa: E402
from solver.results import read_frame, read_series  # noqa: E402


def timed(function, *args):
    start = time.perf_counter()
    value = function(*args)
    return value, time.perf_counter() - start


def material_point_rows():
    rows = []
    for dim in (1, 2, 3):
        error, wall = timed(tp.j2_uniaxial_strain_error, dim)
        rows.append((f"J2 uniaxial strain, {dim}D, to 4 x yield", "max abs(sigma_xx - exact) / yield_stress", error, wall))
    error, wall = timed(tp.j2_uniaxial_stress_error)
    rows.append(("J2 uniaxial stress, to 3 x yield", "max abs(sigma_xx - exact) / yield_stress", error, wall))
    for rate in (0.2, 1e3, 1e5):
        for temperature in (298.0, 600.0, 1000.0):
            error, wall = timed(tp.jc_flow_stress_error, rate, temperature)
            rows.append((f"JC flow stress, shear at {rate:g}/s, T = {temperature:g} K",
                         "abs(q / sigma_f(eps_p, rate, T) - 1)", error, wall))
    for direction, name in ((-1.0, "compression to mu = 0.13"), (1.0, "tension to mu = -0.11")):
        error, wall = timed(tp.mie_gruneisen_error, direction)
        rows.append((f"Mie-Gruneisen, {name}", "max abs(p / EOS - 1)", error, wall))
    (closed_form, balance, _), wall = timed(tp.adiabatic_heating)
    rows.append(("adiabatic heating, shear to 0.5", "abs((T - Tr) / closed form - 1)", abs(closed_form), wall))
    rows.append(("adiabatic heating, shear to 0.5", "abs(rho c dT / (chi W_p) - 1)", abs(balance), wall))
    with tempfile.TemporaryDirectory() as tmp:
        (x, stress, eps_p, exact), wall = timed(tp.plastic_wave_case, Path(tmp))
    t, h = exact["t"], 0.005
    behind = (x > 0.1) & (x < exact["c_p"] * t - 4 * h)
    precursor = (x > exact["c_p"] * t + 4 * h) & (x < exact["c_e"] * t - 2 * h)
    for name, values, reference in (("stress behind the plastic wave", stress[behind], exact["sigma"]),
                                    ("plastic strain behind the plastic wave", eps_p[behind], exact["eps_p"]),
                                    ("stress of the elastic precursor", stress[precursor], exact["sigma_hel"])):
        rows.append((f"J2 bar on a wall, 1D grid, h = 5 mm: {name}", "abs(median / exact - 1)",
                     abs(np.median(values) / reference - 1), wall))
    for name, config in tp.ROTATING.items():
        error, wall = timed(tp.rigid_rotation_error, config)
        rows.append((f"rigid rotation by 90 deg, {name}", "max abs(sigma - R sigma0 R^T) / max abs(sigma0)", error, wall))
    return rows


def copper_bar(folder: Path):
    start = time.perf_counter()
    result = run(ROOT / "examples" / "copper_bar_impact_2d.json", folder)
    wall = time.perf_counter() - start
    first, last = read_frame(result.result_path, 0), read_frame(result.result_path, -1)
    x0, x = first["fields"]["position"], last["fields"]["position"]
    foot = x[:, 1] < x[:, 1].min() + 0.0005
    series = read_series(result.result_path)
    return {
        "status": result.status, "steps": result.steps, "particles": result.particles, "wall": wall,
        "height": (x0[:, 1].max(), x[:, 1].max()), "foot_width": (np.ptp(x0[:, 0]), np.ptp(x[foot, 0])),
        "max_plastic_strain": float(last["fields"]["plastic_strain"].max()),
        "max_temperature": float(last["fields"]["temperature"].max()),
        "kinetic": (series["kinetic_energy"][0], series["kinetic_energy"][-1]),
    }


def main() -> int:
    tp.j2_uniaxial_strain(3, steps=2)             # compile once, outside the timings
    tp.jc_shear(1.0, 298.0, steps=2)
    rows = material_point_rows()
    print("| case | error measure | error | wall time (s) |")
    print("|---|---|---|---|")
    for case, measure, error, wall in rows:
        print(f"| {case} | {measure} | {error:.2g} | {wall:.2f} |")
    with tempfile.TemporaryDirectory() as tmp:
        run(ROOT / "examples" / "copper_bar_impact_2d.json", Path(tmp) / "warm")  # compile cache warm
        bar = copper_bar(Path(tmp) / "bar")
    print()
    print("| example | status | particles | steps | wall time (s) | height (mm) | foot width (mm) | max eps_p | max T (K) | kinetic energy left |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    print(f"| copper_bar_impact_2d | {bar['status']} | {bar['particles']} | {bar['steps']} | {bar['wall']:.1f} "
          f"| {1e3 * bar['height'][0]:.2f} -> {1e3 * bar['height'][1]:.2f} "
          f"| {1e3 * bar['foot_width'][0]:.2f} -> {1e3 * bar['foot_width'][1]:.2f} "
          f"| {bar['max_plastic_strain']:.2f} | {bar['max_temperature']:.0f} "
          f"| {bar['kinetic'][1] / bar['kinetic'][0]:.2%} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
