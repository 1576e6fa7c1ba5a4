"""Johnson-Cook keys a scene does not use are optional: `m` and `specific_heat` without heating."""
import json
from pathlib import Path

import numpy as np
import pytest

from solver.scene import SceneError
from solver.scene_checks import load_scene
from solver.stepper import ExplicitMPM

EXAMPLE = Path(__file__).parents[2] / "examples" / "copper_bar_impact_2d.json"


def copper(taylor_quinney=0.0, drop=("m", "specific_heat"), **body) -> dict:
    scene = json.loads(EXAMPLE.read_text())
    material = next(iter(scene["materials"].values()))
    material["taylor_quinney"] = taylor_quinney
    for key in drop:
        material.pop(key)
    scene["bodies"][0].update(body)
    return scene


def test_an_isothermal_material_needs_neither_m_nor_specific_heat_and_they_change_nothing():
    # without heating T stays room_temperature: T* = 0, so 1 - T*^m = 1 whatever m, and no
    # specific heat enters (dT = 0, the EOS energy rho0 c_p (T - T_room) = 0): the same bits
    runs = []
    for drop in ((), ("m", "specific_heat")):
        sim = ExplicitMPM(load_scene(copper(drop=drop)))
        for _ in range(20):
            sim.advance(sim.stable_time_step(0.5))
        runs.append((sim.particles.x.copy(), sim.particles.stress.copy()))
    assert np.array_equal(runs[0][0], runs[1][0]) and np.array_equal(runs[0][1], runs[1][1])


def test_heating_needs_the_specific_heat_and_m():
    with pytest.raises(SceneError) as caught:
        load_scene(copper(taylor_quinney=0.9))
    assert {e["path"] for e in caught.value.errors} == {"materials.ofhc_copper.m", "materials.ofhc_copper.specific_heat"}
    assert all("taylor_quinney" in e["message"] for e in caught.value.errors)


def test_a_body_above_room_temperature_needs_m():
    with pytest.raises(SceneError) as caught:
        load_scene(copper(initial_temperature=600.0))
    assert [e["path"] for e in caught.value.errors] == ["materials.ofhc_copper.m"]
    load_scene(copper(drop=("specific_heat",), initial_temperature=600.0))   # with m: fine
