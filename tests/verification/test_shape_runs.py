"""Every shape function (and APIC) through `mpm run`: the column of
examples/column_under_gravity_2d.json settling on its stick floor for 0.05 s.

What must hold whatever the shape function: the run completes (no instability:
the mass cut-off keeps nearly empty nodes bounded), the adaptive time step is
the documented dt = cfl h / (c + |v|) (at t = 0, v = 0: cfl h / c), and the
floor holds the column: its centre of mass sinks by less than free fall
g t^2 / 2 would take it, and by more than 0 (gravity acts; the column
compresses by its elastic settlement, rho g H^2 / (2 M) ~ 1e-3 m, plus the
transient).
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from solver import cli
from solver.results import read_frame, read_series

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "column_under_gravity_2d.json"
END = 0.05


def column(shape_function: str, transfer: str) -> dict:
    scene = json.loads(EXAMPLE.read_text())
    scene["method"].update(shape_function=shape_function, transfer=transfer)
    scene["time"]["end"] = END
    scene["output"]["frames"] = 2
    if shape_function == "quadratic_bspline":
        # no node beyond the grid: pad the floor by a cell and hold the floor nodes instead of a wall
        h = scene["grid"]["cell_size"]
        scene["grid"]["lower"][1] = -h
        scene["boundary_conditions"] = [{"type": "velocity", "velocity": [0.0, 0.0],
                                         "where": {"type": "box", "lower": [-1.0, -1.0], "upper": [1.0, 1e-9]}}]
    return scene


@pytest.mark.parametrize("shape_function, transfer", [
    ("gimp", "flip"), ("cpgimp", "flip"), ("quadratic_bspline", "flip"), ("cubic_bspline", "flip"),
    ("quadratic_bspline", "apic"),
])
def test_column_settles_with_every_shape_function(tmp_path, shape_function, transfer):
    scene = column(shape_function, transfer)
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    assert cli.main(["run", str(path), "-o", str(tmp_path / "out"), "--progress", "none"]) == 0
    result = tmp_path / "out" / "result.h5"
    series = read_series(result)
    material = scene["materials"]["elastic"]
    E, nu, rho = material["youngs_modulus"], material["poisson_ratio"], material["density"]
    c = math.sqrt(E * (1 - nu) / ((1 + nu) * (1 - 2 * nu)) / rho)
    assert series["dt"][0] == pytest.approx(scene["time"]["cfl"] * scene["grid"]["cell_size"] / c, rel=1e-12)
    first, last = read_frame(result, 0), read_frame(result, -1)
    assert last["time"] == pytest.approx(END)
    assert np.all(np.isfinite(last["fields"]["stress"]))
    m = first["fields"]["mass"]
    sink = float(np.sum(m * (first["fields"]["position"][:, 1] - last["fields"]["position"][:, 1])) / m.sum())
    assert 0.0 < sink < 0.5 * 9.81 * END**2
