"""The scene summary: counts, steps, memory and run-time estimates, without allocation."""

import math
import tracemalloc

import pytest

from solver import capabilities, cost
from solver.scene_checks import load_scene
from solver.summary import PROCESS_BASELINE_BYTES, memory_estimate, particle_bytes, summarize

RUBBER = {"model": "linear_elastic", "density": 1000, "youngs_modulus": 1000, "poisson_ratio": 0.3}


def two_disks(dt=0.001) -> dict:
    """VERIFICATION_CASES E2 (Karamelo listing 2)."""
    return {
        "dimension": 2,
        "grid": {"lower": [-0.5, -0.5], "upper": [0.5, 0.5], "cell_size": 0.05},
        "materials": {"rubber": RUBBER},
        "bodies": [
            {"name": "disk1", "material": "rubber", "initial_velocity": [0.1, 0.1],
             "geometry": {"type": "sphere", "center": [-0.3, -0.3], "radius": 0.2}},
            {"name": "disk2", "material": "rubber", "initial_velocity": [-0.1, -0.1],
             "geometry": {"type": "sphere", "center": [0.3, 0.3], "radius": 0.2}},
        ],
        "time": {"end": 3.5, "dt": dt},
    }


def test_two_disk_counts():
    summary = summarize(load_scene(two_disks()))
    assert summary.particles == 416 and summary.particles_per_body == [208, 208]
    assert summary.grid_shape == [20, 20] and summary.grid_nodes == 21 * 21
    assert summary.dt == 0.001 and summary.estimated_steps == 3500  # 3.5 s / 0.001 s, E2


def test_two_disk_memory_and_run_time():
    scene = load_scene(two_disks())
    summary = summarize(scene)
    # 2D, linear elastic, fused backend: per particle, 8-byte values: position 2, velocity 2,
    # F 4, L 4, stress 9, mass, volume, volume0, id 4, MUSL's v_pic 2 = 27; plus the 4-byte body
    # index. Per node: mass 1, momentum, force (which then holds v_old: MUSL), v_new 6, and each
    # thread beyond the first a copy of mass, momentum and force (5); a 1-byte mask. A frame forms
    # no field here (position and velocity are the state's arrays); 2 frames' bookkeeping, the
    # energy rows. Then the process's baseline; the preview of 416 points is less than the arrays.
    threads = cost.planned_threads(scene, 416)
    held = 416 * (27 * 8 + 4) + 441 * (7 * 8 + (threads - 1) * 5 * 8 + 1)
    parts = memory_estimate(scene, 416, 441)
    assert parts["bodies"] == 416 * (27 * 8 + 4) + 2 * 4096 and parts["grid"] == 441 * (7 * 8 + (threads - 1) * 40 + 1)
    assert summary.memory_bytes == PROCESS_BASELINE_BYTES + max(sum(parts.values()), 600 * 416)
    assert sum(parts.values()) > held
    # the run time is the cost model's (tests/unit/test_cost.py), with the scene's counts
    # (and the compilation of its variant when this machine has not compiled it yet)
    expected = cost.estimate_seconds(load_scene(two_disks()), [208, 208], 441, 3500)
    assert summary.estimated_compile_seconds == cost.compile_seconds(load_scene(two_disks()), threads)
    assert summary.estimated_run_seconds == pytest.approx(expected + summary.estimated_compile_seconds, rel=1e-12)


def test_contact_fields_multiply_the_grid_memory():
    scene = two_disks()
    scene["contact"] = {"model": "friction"}
    one, two = (memory_estimate(load_scene(s), 416, 441)["grid"] for s in (two_disks(), scene))
    # two bodies: two fields of the nodal arrays, each with its presence and normal (1 + 2 values)
    assert two - 1 * 441 == 2 * (one - 441 + 441 * 3 * 8)


def test_adaptive_step_estimate():
    summary = summarize(load_scene(two_disks(dt=None)))
    # dt = cfl h / (c + |v|max): c = 1.1602 (E2 [derived]), |v| = 0.1 sqrt(2)
    c = math.sqrt((7500 / 13 + 2 * 5000 / 13) / 1000)
    dt = 0.5 * 0.05 / (c + 0.1 * math.sqrt(2))
    assert summary.dt == pytest.approx(dt, rel=1e-12)
    assert summary.estimated_steps == math.ceil(3.5 / dt)


def test_expression_velocities_are_sampled_over_the_body():
    scene = two_disks(dt=None)
    # a box body: |v| peaks at its far corner, x = y = 0.5, where v = (5, 5)
    scene["bodies"][1]["geometry"] = {"type": "box", "lower": [0.1, 0.1], "upper": [0.5, 0.5]}
    scene["bodies"][1]["initial_velocity"] = ["10*x", "10*y"]
    summary = summarize(load_scene(scene))
    c = math.sqrt((7500 / 13 + 2 * 5000 / 13) / 1000)
    assert summary.dt == pytest.approx(0.5 * 0.05 / (c + 5 * math.sqrt(2)), rel=1e-12)


def test_velocities_outside_the_body_do_not_count():
    scene = two_disks(dt=None)
    # the disk of radius 0.2 at (0.3, 0.3): |v| = 10 r is at most 10 (0.3 sqrt(2) + 0.2) on it, and
    # 10 * 0.5 sqrt(2) at its box's corner, where there is no particle; at least its centre's 10 * 0.3 sqrt(2)
    scene["bodies"][1]["initial_velocity"] = ["10*x", "10*y"]
    summary = summarize(load_scene(scene))
    c = math.sqrt((7500 / 13 + 2 * 5000 / 13) / 1000)
    fastest = 0.5 * 0.05 / summary.dt - c
    assert 10 * 0.3 * math.sqrt(2) <= fastest <= 10 * (0.3 * math.sqrt(2) + 0.2)


def test_gas_wave_speed_comes_from_the_body(monkeypatch):
    monkeypatch.setattr(capabilities, "MATERIAL_MODELS", capabilities.MATERIAL_MODELS | {"ideal_gas"})
    scene = two_disks(dt=None)
    scene["materials"] = {"air": {"model": "ideal_gas", "gamma": 1.4}}
    for body in scene["bodies"]:
        body.update(material="air", initial_density=1.0, initial_pressure=1.0, initial_velocity=None)
    scene["bodies"][1].update(initial_density=0.125, initial_pressure=0.1)  # Sod's right state
    summary = summarize(load_scene(scene))
    fastest = max(math.sqrt(1.4), math.sqrt(1.4 * 0.1 / 0.125))
    assert summary.dt == pytest.approx(0.5 * 0.05 / fastest, rel=1e-12)


def test_shape_function_support_enters_the_memory(monkeypatch):
    monkeypatch.setattr(capabilities, "SHAPE_FUNCTIONS", capabilities.SHAPE_FUNCTIONS | {"cubic_bspline"})
    scene = two_disks()
    scene["method"] = {"shape_function": "cubic_bspline"}
    scene = load_scene(scene)
    # cubic B-splines step on the general backend, which stores the stencil: 16 nodes per
    # particle, a weight, 2 gradient components and an index each, instead of the fused v_pic (2)
    assert cost.backend_name(scene) == "general"
    assert particle_bytes(scene) == (27 - 2 + 16 * 4) * 8 + 4


def test_3d_run_time_is_the_cost_models():
    scene = {
        "dimension": 3,
        "grid": {"lower": [0, 0, 0], "upper": [1, 1, 1], "cell_size": 0.25},
        "materials": {"rubber": RUBBER},
        "bodies": [{"name": "block", "material": "rubber", "particles_per_cell": 1,
                    "geometry": {"type": "box", "lower": [0, 0, 0], "upper": [0.5, 0.5, 1]}}],
        "time": {"end": 1.0, "dt": 0.01},
    }
    summary = summarize(load_scene(scene))
    assert summary.particles == 2 * 2 * 4 and summary.grid_nodes == 125
    expected = cost.estimate_seconds(load_scene(scene), [16], 125, 100) + cost.compile_seconds(load_scene(scene), 1)
    assert summary.estimated_run_seconds == pytest.approx(expected, rel=1e-12)


def test_no_allocation_proportional_to_the_scene():
    # 8 million particles: their positions alone would take 192 MB.
    scene = {
        "dimension": 3,
        "grid": {"lower": [0, 0, 0], "upper": [1, 1, 1], "cell_size": 0.01},
        "materials": {"rubber": RUBBER},
        "bodies": [{"name": "block", "material": "rubber",
                    "geometry": {"type": "box", "lower": [0, 0, 0], "upper": [1, 1, 1]}}],
        "time": {"end": 1.0, "dt": 0.005},
    }
    scene = load_scene(scene)
    tracemalloc.start()
    try:
        summary = summarize(scene)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert summary.particles == 8_000_000
    assert peak < 50e6


def test_a_flip_blend_below_one_on_a_long_elastic_run_is_warned_about():
    # two disks, c = 1.16, longest side 0.4: one axial period 4 * 0.4 / 1.16 = 1.4 < end = 3.5
    warnings = summarize(load_scene(two_disks())).warnings
    assert [w["path"] for w in warnings] == ["method.flip_ratio"] and "7.6 %" in warnings[0]["message"]
    for change in ({"method": {"transfer": "flip", "flip_ratio": 1.0}}, {"method": {"transfer": "pic"}},
                   {"damping": {"type": "viscous", "coefficient": 0.1}}):
        assert summarize(load_scene({**two_disks(), **change})).warnings == []
    short = two_disks()
    short["time"]["end"] = 1.0   # less than one period: nothing to damp yet
    assert summarize(load_scene(short)).warnings == []


def test_the_memory_estimate_counts_what_a_3d_johnson_cook_run_allocates():
    """memory_estimate's parts against the bytes the run's arrays take (tracemalloc traces numpy's
    allocations): the example Taylor bar, made and stepped twice, one frame's fields formed. The
    kernels are loaded by a first simulation, untraced, so that no compilation is counted. 10 %:
    what the estimate leaves out is the bookkeeping (the scene, the kernels' argument tuples, a
    few arrays per material), a few hundred kB beside the 30 MB of arrays (benchmarks/memory.py
    measures the process's peak against memory_bytes, within 15 % from 0.3 to 12.4 M particles)."""
    from solver.examples import load_example
    from solver.fields import frame_fields
    from solver.runner import make_simulation

    scene = load_example("taylor_bar_3d")
    scene["output"]["fields"] = ["position", "velocity", "stress", "plastic_strain", "deformation_gradient"]
    scene = load_scene(scene)
    warm = make_simulation(scene)
    warm.advance(warm.stable_time_step(scene.time.cfl))
    del warm
    tracemalloc.start()
    try:
        sim = make_simulation(scene)
        for _ in range(2):
            sim.advance(sim.stable_time_step(scene.time.cfl))
        fields = frame_fields(sim, scene.output.fields)
        formed = [fields[name] for name in fields]   # (of them only the stress is formed, not a view)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    del formed
    summary = summarize(scene)
    parts = memory_estimate(scene, summary.particles, summary.grid_nodes)
    assert sim.particles.count == summary.particles
    assert sum(parts.values()) == pytest.approx(peak, rel=0.10)


def test_the_reference_position_field_keeps_and_counts_the_seeded_positions(tmp_path):
    """An update-Lagrangian scene keeps X only for the `reference_position` output field:
    the memory estimate counts its dim values a particle, and the run writes the seeded
    positions while the particles move."""
    import numpy as np

    from solver import run
    from solver.results import read_frame
    scene = two_disks()
    asked = two_disks()
    asked["output"] = {**asked.get("output", {}), "fields": ["position", "reference_position"], "frames": 2}
    assert particle_bytes(load_scene(asked)) - particle_bytes(load_scene(scene)) == 8 * 2
    asked["time"] = {**asked["time"], "end": 20 * asked["time"]["dt"]}
    result = run(asked, tmp_path / "run")
    first, last = (read_frame(result.result_path, i)["fields"] for i in (0, -1))
    assert np.array_equal(last["reference_position"], first["position"])
    assert not np.array_equal(last["position"], first["position"])


def test_a_run_lets_its_simulation_go_before_it_draws_the_previews(tmp_path, monkeypatch):
    """The previews read the last frame back from the file: drawn beside the particles' and
    the grid's arrays, they made the peak at 0.3 M particles 1.13x memory_bytes, which takes
    the larger of the two (the run's own local name for the simulation held it)."""
    import gc

    from solver import preview, run
    from solver.stepper import ExplicitMPM
    alive = []

    def finish_outputs(out_dir, scene):
        gc.collect()
        alive.append(sum(isinstance(o, ExplicitMPM) for o in gc.get_objects()))

    monkeypatch.setattr(preview, "finish_outputs", finish_outputs)
    scene = two_disks()
    scene["time"] = {**scene["time"], "end": 5 * scene["time"]["dt"]}
    assert run(scene, tmp_path).status == "complete"
    assert alive == [0]
