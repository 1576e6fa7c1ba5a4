"""E18: orthogonal machining of a high-strength steel by a rigid tool (Karamelo 4.4), TLMPM.

examples/machining_2d.json at coarser grids (tests/verification/machining.py). Karamelo
reports plots only; the references are Merchant's frictionless cutting model (the cutting
force band: shear flow stress between A / sqrt 3 and the fully hardened sigma(eps) / sqrt 3
on the shear plane) and the directions of a frictionless tool's forces.

- fast (40 x 10 cells, 400 particles, 0.1 mm of cut): a chip rises ahead of the tool, the
  tool's force lies in the cone its two faces can push in, and the cutting force has
  reached Merchant's band.
- slow (80 x 20 cells, 1600 particles, 0.25 mm of cut): the cutting force levels off, and
  the plateau lies in Merchant's band.
"""
import math

import numpy as np
import pytest

from machining import DEPTH, HEIGHT, chip_rise, cutting_forces, machining_scene, merchant, plateau, rake_angle, \
    tool_travel
from mpm_cases import run_scene


@pytest.fixture(scope="module")
def steel():
    return machining_scene()["materials"]["steel"]


def _run(tmp_path_factory, cells_x, cells_y, cut, energies):
    scene = machining_scene(cells_x, cells_y, cut, frames=3, energies=energies)
    case = run_scene(scene, tmp_path_factory.mktemp("machining"))
    case.scene = scene
    return case


@pytest.fixture(scope="module")
def coarse(tmp_path_factory):
    return _run(tmp_path_factory, 40, 10, 0.1e-3, 10)


def test_a_chip_rises_ahead_of_the_tool(coarse):
    assert coarse.result.status == "complete"
    last = coarse.frame(-1)
    # Elastically the surface would rise by about (A / E) t0 = 0.7 um; plastic flow up the rake
    # face lifts the chip by about the tool's travel once the shear plane has formed (Merchant:
    # chip speed v sin(phi) / cos(phi - alpha) = v here). A quarter of the depth of cut (37.5 um,
    # more than a cell) is far above the first and well below the second after 0.1 mm.
    rise = chip_rise(last, last["time"])
    assert rise > DEPTH / 4, rise
    # the material below the cut line stays below the original surface
    x = last["fields"]["position"]
    assert x[:, 1].max() < HEIGHT + 3 * DEPTH


def test_a_frictionless_tool_pushes_along_its_faces(coarse):
    """The rake face pushes the material along its normal, so it pulls the tool down with
    F_t = -tan(alpha) F_c; the flank can only push the tool up: F_t >= -tan(alpha) F_c."""
    fc, ft = cutting_forces(coarse.series())
    touching = fc > 0
    assert touching.sum() > 10
    bound = -math.tan(rake_angle(coarse.scene)) * fc[touching]
    assert np.all(ft[touching] >= bound - 1e-9 * np.abs(bound))
    assert np.all(fc >= -1e-9 * np.abs(fc).max())   # the material never pulls the tool forward


def test_the_cutting_force_reaches_merchants_band(coarse, steel):
    s = coarse.series()
    band = merchant(steel)
    fc, _ = cutting_forces(s)
    late = tool_travel(s) > 0.075e-3
    assert band["low"] <= fc[late].mean() <= band["high"], (fc[late].mean(), band)


@pytest.mark.slow
def test_the_cutting_force_levels_off_in_merchants_band(tmp_path_factory, steel):
    case = _run(tmp_path_factory, 80, 20, 0.25e-3, 20)
    s = case.series()
    band = merchant(steel)
    first, _ = plateau(s, 0.1e-3)
    second, spread = plateau(s, 0.175e-3)
    print(f"machining 80 x 20: F_c {first / 1e3:.0f} kN/m after 0.1 mm, {second / 1e3:.0f} (sd {spread / 1e3:.0f}) "
          f"after 0.175 mm; Merchant {band['low'] / 1e3:.0f}-{band['high'] / 1e3:.0f}, mean {band['mean'] / 1e3:.0f}")
    assert band["low"] <= second <= band["high"]
    assert abs(second - first) < 0.15 * second   # levelled off: the last third within 15 % of the mean after 0.1 mm
