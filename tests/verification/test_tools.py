"""Tools (issue 15, Karamelo 4.4): rigid obstacles that push particles by a Hertz penalty
(solver/tools.py). The reaction against the momentum the particles receive, in ULMPM and
TLMPM; the scene's errors. The numbers are in docs/benchmarks.md.
"""
from __future__ import annotations

import copy

import numpy as np
import pytest

from solver import series
from solver.scene import SceneError, load_scene
from solver.stepper import ExplicitMPM

E, NU, RHO = 1e6, 0.3, 1000.0


def block_and_wedge(formulation: str = "ulmpm", friction: float = 0.2) -> dict:
    """A free elastic block (no gravity, no walls) that a wedge-shaped tool cuts into."""
    return {
        "dimension": 2,
        "method": {"formulation": formulation, "scheme": "musl", "shape_function": "linear", "transfer": "flip"},
        "grid": {"lower": [0, 0], "upper": [1, 1], "cell_size": 0.05},
        "materials": {"m": {"model": "linear_elastic", "density": RHO, "youngs_modulus": E, "poisson_ratio": NU}},
        "bodies": [{"name": "block", "material": "m",
                    "geometry": {"type": "box", "lower": [0.3, 0.3], "upper": [0.7, 0.6]}}],
        "tools": [{"name": "cutter", "geometry": {"type": "polygon", "vertices": [[0.42, 0.58], [0.62, 0.58],
                                                                                [0.5, 0.8]]},
                   "velocity": [0.2, "-min(t / 0.01, 1)"], "stiffness": 2.0, "friction": friction}],
        "time": {"end": 0.1},
    }


@pytest.mark.parametrize("formulation", ["ulmpm", "tlmpm"])
def test_reaction_is_minus_the_momentum_the_particles_receive(formulation):
    """With no other force on the block, its momentum changes only by the tool's forces:
    the grid's internal forces sum to zero and the weights are a partition of unity, so
    p(t1) - p(t0) = -reaction (t1 - t0) to round-off, on both axes (friction gives x)."""
    sim = ExplicitMPM(load_scene(block_and_wedge(formulation)))
    for _ in range(3):
        before, t0 = series.momentum(sim), sim.time
        while sim.time < t0 + 0.015:
            sim.advance(sim.stable_time_step(0.5))
        after, reaction = series.momentum(sim), sim.reactions()
        for axis in "xy":
            change = after[f"momentum_block_{axis}"] - before[f"momentum_block_{axis}"]
            expected = -reaction[f"reaction_cutter_{axis}"] * (sim.time - t0)
            assert change == pytest.approx(expected, rel=1e-9, abs=1e-12 * abs(after["momentum_block_y"]))
    assert after["momentum_block_y"] < 0 and reaction["reaction_cutter_y"] > 0   # pushed down, pushed back
    assert after["momentum_block_x"] > 0   # friction drags the block along with the tool


def test_a_frictionless_tool_pushes_along_the_normal_only():
    """A flat-bottomed tool moving straight down on a block: the forces are vertical."""
    scene = block_and_wedge(friction=0.0)
    scene["tools"][0]["geometry"] = {"type": "box", "lower": [0.4, 0.58], "upper": [0.6, 0.8]}
    scene["tools"][0]["velocity"] = [0.0, -1.0]
    sim = ExplicitMPM(load_scene(scene))
    while sim.time < 0.02:
        sim.advance(sim.stable_time_step(0.5))
    reaction = sim.reactions()
    assert reaction["reaction_cutter_y"] > 0
    assert abs(reaction["reaction_cutter_x"]) <= 1e-9 * reaction["reaction_cutter_y"]


def test_the_tool_work_enters_the_energy_balance():
    """tool_work = dt sum f_p . v_p is the energy the block received: kinetic plus strain
    energy do not exceed it (FLIP and the penalty's stored energy lose some)."""
    sim = ExplicitMPM(load_scene(block_and_wedge(friction=0.0)))
    while sim.time < 0.03:
        sim.advance(sim.stable_time_step(0.5))
    e = sim.energies()
    assert e.tool_work > 0
    assert 0.5 * e.tool_work < e.kinetic + e.strain <= e.tool_work


# -- bad input ----------------------------------------------------------------------------

def errors(scene: dict) -> dict[str, str]:
    with pytest.raises(SceneError) as caught:
        load_scene(scene)
    return {e["path"]: e["message"] for e in caught.value.errors}


def with_tool(**changes) -> dict:
    scene = block_and_wedge()
    scene["tools"][0].update(changes)
    return scene


def test_tool_errors_name_the_field():
    assert "must be > 0" in errors(with_tool(stiffness=-1.0))["tools[0].stiffness"]
    assert ">= 0" in errors(with_tool(friction=-0.1))["tools[0].friction"]
    assert "must have 2 components" in errors(with_tool(velocity=[1.0, 0.0, 0.0]))["tools[0].velocity"]
    assert "unknown name 'x'" in errors(with_tool(velocity=[0.0, "x * t"]))["tools[0].velocity[1]"]
    twice = block_and_wedge()
    twice["tools"].append(copy.deepcopy(twice["tools"][0]))
    assert "already the name of tools[0]" in errors(twice)["tools[1].name"]
    cylinder = with_tool(geometry={"type": "cylinder", "center": [0, 0, 0], "radius": 1, "height": 1})
    assert any(path.startswith("tools[0].geometry") for path in errors(cylinder))


def test_tool_geometry_must_fit_the_dimension():
    scene = block_and_wedge()
    scene.update(dimension=3, grid={"lower": [0, 0, 0], "upper": [1, 1, 1], "cell_size": 0.1})
    scene["bodies"][0]["geometry"] = {"type": "box", "lower": [0.3, 0.3, 0.3], "upper": [0.7, 0.6, 0.7]}
    scene["tools"][0]["velocity"] = [0, 0, -1]
    assert "a polygon is a 2D geometry" in errors(scene)["tools[0].geometry.type"]


def test_tool_name_may_not_be_a_rigid_body_name():
    scene = block_and_wedge()
    scene["materials"]["steel"] = {"model": "rigid", "density": 7800}
    scene["bodies"].append({"name": "cutter", "material": "steel",
                            "geometry": {"type": "box", "lower": [0.1, 0.1], "upper": [0.2, 0.2]}})
    assert "already the name of bodies[1]" in errors(scene)["tools[0].name"]


def test_tools_need_a_material_with_a_shear_modulus():
    scene = block_and_wedge()
    scene["materials"]["m"] = {"model": "fluid", "density": 1000, "bulk_modulus": 2e6, "viscosity": 1e-3}
    assert "has none" in errors(scene)["tools"]
