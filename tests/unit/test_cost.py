"""The run-time cost model (solver/cost.py): its formula, where it is read from, thread scaling."""
import json

import pytest

from solver import cost
from solver.scene_checks import load_scene

RUBBER = {"model": "linear_elastic", "density": 1000, "youngs_modulus": 1000, "poisson_ratio": 0.3}
STEEL = {"model": "j2_plasticity", "density": 7800, "youngs_modulus": 2e11, "poisson_ratio": 0.3,
         "yield_stress": 7e8, "hardening_modulus": 3e8}


def scene(**method) -> dict:
    return {"dimension": 2, "method": method,
            "grid": {"lower": [0, 0], "upper": [1, 1], "cell_size": 0.1},
            "materials": {"rubber": RUBBER, "steel": STEEL},
            "bodies": [{"name": "a", "material": "rubber", "geometry": {"type": "box", "lower": [0.1, 0.1],
                                                                        "upper": [0.4, 0.4]}},
                       {"name": "b", "material": "steel", "geometry": {"type": "box", "lower": [0.5, 0.5],
                                                                       "upper": [0.9, 0.9]}}],
            "time": {"end": 1.0, "dt": 1e-5}, "output": {"frames": 11}, "parallel": {"threads": 1}}


MODEL = cost.CostModel(
    startup_seconds=2.0, frame_particle_seconds=1e-7,
    step_seconds={"2/fused": 1e-4, "2/general": 2e-4}, node_seconds={"2/fused": 1e-8, "2/general": 2e-8},
    particle_seconds={"2/fused/ulmpm/linear": 1e-7, "2/general/ulmpm/linear": 3e-7},
    material_seconds={"2/j2_plasticity": 5e-8},
    factors={"fused/pic": 0.9, "fused/musl": 1.0}, thread_scaling={"2/fused": {"threads": 2, "speedup": 1.6}})


def test_estimate_adds_start_up_frames_and_the_steps_of_each_material():
    s = load_scene(scene(transfer="pic"))
    seconds = cost.estimate_seconds(s, [100, 300], 121, 50, MODEL)
    # fused 2D step: a + b N + (c f P + m P_steel), one thread; plus start-up and 11 frames of 400 particles
    step = 1e-4 + 1e-8 * 121 + 1e-7 * 0.9 * 400 + 5e-8 * 300
    assert seconds == pytest.approx(2.0 + 1e-7 * 400 * 11 + 50 * step, rel=1e-12)


def test_threads_scale_the_particle_and_node_work_by_amdahls_law():
    document = scene()
    document["parallel"]["threads"] = 4
    s = load_scene(document)
    one = load_scene(scene())
    # measured 1.6 at 2 threads: parallel share p = (1 - 1/1.6) / (1 - 1/2) = 0.75; at 4: 1 / (0.25 + 0.75/4)
    speedup = 1 / (0.25 + 0.75 / 4)
    assert cost.ThreadScaling(threads=2, speedup=1.6).at(4) == pytest.approx(speedup, rel=1e-12)
    work = 1e-8 * 121 + 1e-7 * 400 + 5e-8 * 300
    fixed = 2.0 + 1e-7 * 400 * 11 + 50 * 1e-4
    if cost.planned_threads(s, 400) == 4:   # numba's pool may be smaller than 4 here
        assert cost.estimate_seconds(s, [100, 300], 121, 50, MODEL) == pytest.approx(fixed + 50 * work / speedup)
    assert cost.estimate_seconds(one, [100, 300], 121, 50, MODEL) == pytest.approx(fixed + 50 * work)


def test_an_uncalibrated_shape_function_scales_the_linear_cost_by_its_nodes():
    s = load_scene(scene(shape_function="cubic_bspline"))   # general backend, 4 x 4 nodes against 2 x 2
    assert cost.particle_step_seconds(MODEL, s, "general") == pytest.approx(3e-7 * 4, rel=1e-12)


def test_this_machines_calibration_wins_over_the_shipped_model(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    assert cost.load_model().source == str(cost.SHIPPED)
    path = cost.calibration_path()
    path.parent.mkdir(parents=True)
    path.write_text(MODEL.model_dump_json())
    assert cost.load_model().source == str(path) and cost.load_model().startup_seconds == 2.0
    path.write_text(json.dumps({"version": 0}))   # an old or broken file is ignored
    assert cost.load_model().source == str(cost.SHIPPED)


def test_the_shipped_model_covers_every_backend_and_material():
    model = cost.CostModel.model_validate_json(cost.SHIPPED.read_text())
    for dim in (2, 3):
        for backend in ("fused", "general"):
            assert f"{dim}/{backend}" in model.step_seconds and f"{dim}/{backend}/ulmpm/linear" in model.particle_seconds
    for name in ("neo_hookean", "j2_plasticity", "johnson_cook", "fluid", "ideal_gas"):
        assert f"2/{name}" in model.material_seconds and f"3/{name}" in model.material_seconds


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_every_calibration_block_is_a_valid_scene_of_the_size_asked(dim):
    from solver import calibrate
    from solver.summary import summarize

    for material in calibrate.MATERIALS:
        summary = summarize(load_scene(calibrate.block_scene(dim, calibrate.BLOCK_PARTICLES[dim], material=material)))
        assert 0.5 < summary.particles / calibrate.BLOCK_PARTICLES[dim] < 2
    small = summarize(load_scene(calibrate.block_scene(dim, 1000)))
    wide = summarize(load_scene(calibrate.block_scene(dim, 1000, grid_factor=4.0)))
    assert wide.particles == small.particles and 3 < wide.grid_nodes / small.grid_nodes < 5


def test_threads_that_measured_slower_than_one_stay_slower():
    assert cost.ThreadScaling(threads=2, speedup=0.5).at(4) == 0.5 and cost.ThreadScaling(threads=2, speedup=0.5).at(1) == 1


def test_body_force_expressions_and_the_kinds_start_up_are_counted():
    from solver.expressions import compile_expression

    model = MODEL.model_copy(update={"expression_seconds": 2e-9, "startup_extra_seconds": {"2/general/gimp": 3.0}})
    document = scene(shape_function="gimp")
    document["body_force"] = ["sin(x) * t", 0.0]
    s = load_scene(document)
    plain = load_scene(scene(shape_function="gimp"))
    operations = compile_expression("sin(x) * t", ("x", "y", "z", "X", "Y", "Z", "t")).operations
    difference = cost.estimate_seconds(s, [100, 300], 121, 50, model) - cost.estimate_seconds(plain, [100, 300], 121, 50, model)
    assert difference == pytest.approx(50 * 2e-9 * operations * 400, rel=1e-9)
    assert cost.estimate_seconds(plain, [100, 300], 121, 50, model) - cost.estimate_seconds(plain, [100, 300], 121, 50, MODEL) \
        == pytest.approx(3.0)
