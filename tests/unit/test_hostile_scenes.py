"""Scenes built to hurt (issue 49): each is refused by arithmetic on the scene, fast, with
an error naming the field and the rule, and never with an exception other than SceneError
(the service would answer that 500)."""
import copy
import math
import time

import numpy as np
import pytest

from solver import geometry
from solver.scene import SceneError
from solver.scene_checks import Limits, load_scene
from solver.summary import empty_bodies, memory_estimate, summarize

from test_scene_validation import two_disks

SERVICE_LIMITS = Limits(max_particles=2_000_000, max_grid_nodes=4_000_000, max_steps=10_000_000,
                        max_memory_bytes=8 * 2**30)


def _errors(scene: dict, limits: Limits | None = SERVICE_LIMITS) -> list[dict]:
    with pytest.raises(SceneError) as caught:
        load_scene(scene, limits)
    return caught.value.errors


def _changed(change) -> dict:
    scene = copy.deepcopy(two_disks())
    change(scene)
    return scene


class TestFrames:
    def test_a_billion_frames_is_refused_at_output_frames(self):
        errors = _errors(_changed(lambda s: s["output"].update(frames=10**9)))
        assert [e["path"] for e in errors] == ["output.frames"]
        assert "3500 time steps (end / dt) + 1" in errors[0]["message"]

    def test_one_frame_a_step_and_the_first_is_the_most(self):
        load_scene(_changed(lambda s: s["output"].update(frames=3501)))
        assert [e["path"] for e in _errors(_changed(lambda s: s["output"].update(frames=3502)))] == ["output.frames"]

    def test_up_to_the_default_count_is_always_allowed(self):
        def coarse(frames):   # 10 steps
            return lambda s: (s["time"].update(end=1.0, dt=0.1, allow_unstable_dt=True), s["output"].update(frames=frames))
        load_scene(_changed(coarse(51)))
        assert [e["path"] for e in _errors(_changed(coarse(52)))] == ["output.frames"]

    def test_an_adaptive_run_is_bounded_by_max_steps(self):
        def change(s):
            s["time"] = {"end": 3.5, "max_steps": 1000}
            s["output"]["frames"] = 1002
        errors = _errors(_changed(change))
        assert errors[0]["path"] == "output.frames" and "time.max_steps" in errors[0]["message"]

    def test_the_frame_schedule_holds_no_list_of_the_frames(self):
        from solver.runner import _FrameSchedule
        schedule = _FrameSchedule(1.0, 10**12)   # a list would be terabytes
        assert schedule.until_next(0.0) == 0.0
        schedule.next = 1
        assert schedule.until_next(0.0) == pytest.approx(1e-12)


class TestMemory:
    def test_the_estimate_counts_frames_bodies_and_series(self):
        scene = load_scene(two_disks())
        parts = memory_estimate(scene, 416, 441)
        assert set(parts) == {"bodies", "grid", "output.frames", "output.series"}
        more = load_scene(_changed(lambda s: s["output"].update(series=["momentum", "center_of_mass"])))
        assert memory_estimate(more, 416, 441)["output.series"] > parts["output.series"]

    def test_over_the_memory_limit_names_the_largest_part(self):
        # per-body series columns (momentum, centre of mass) x 20,000 rows for 200 bodies
        def change(s):
            s["bodies"] = [{**s["bodies"][0], "name": f"b{i}", "particles_per_cell": 1,
                            "geometry": {"type": "box", "lower": [-0.5 + 0.005 * i, -0.5],
                                         "upper": [-0.5 + 0.005 * i + 0.004, 0.5]}} for i in range(200)]
            s["output"]["series"] = ["momentum", "center_of_mass"]
            s["time"]["end"] = 100.0
            s["time"]["max_steps"] = 10**6
        errors = _errors(_changed(change), Limits(max_memory_bytes=10**8))
        assert [(e["path"], e["limit"]) for e in errors] == [("output.series", "max_memory_bytes")]
        assert "over the limit of" in errors[0]["message"] and "output.series" in errors[0]["message"]

    def test_within_the_limit_nothing_is_said(self):
        load_scene(two_disks(), SERVICE_LIMITS)


class TestOverflow:
    def test_a_grid_of_infinite_extent_is_a_grid_error(self):
        errors = _errors(_changed(lambda s: s["grid"].update(lower=[-1e308, -1e308], upper=[1e308, 1e308])))
        assert {e["path"] for e in errors} == {"grid"}
        assert "not a finite number of cells" in errors[0]["message"]

    def test_huge_cells_are_not_an_overflow(self):
        scene = load_scene(_changed(lambda s: s["grid"].update(cell_size=1e300)), SERVICE_LIMITS)
        assert empty_bodies(scene, summarize(scene).particles_per_body)   # then refused: no particle

    def test_the_conduction_limit_of_huge_cells_is_no_overflow(self):
        from solver.thermal_schema import conduction_time_step

        def change(s):
            s["grid"]["cell_size"] = 1e300
            s["materials"]["rubber"].update(thermal_conductivity=1.0, specific_heat=1.0)
        found = conduction_time_step(load_scene(_changed(change), stability=False))
        assert found is None or found[0] == math.inf or found[0] > 0

    def test_end_over_dt_past_any_integer_is_a_time_error(self):
        errors = _errors(_changed(lambda s: s["time"].update(end=1e308, dt=1e-308)))
        assert [e["path"] for e in errors] == ["time.dt"] and "more than max_steps" in errors[0]["message"]


class TestEmptyBodies:
    def test_a_body_between_the_particle_positions_is_named(self):
        scene = load_scene(_changed(lambda s: s["bodies"][1]["geometry"].update(radius=0.001)))
        problems = empty_bodies(scene, summarize(scene).particles_per_body)
        assert [path for path, _ in problems] == ["bodies[1]"] and "'disk2' seeds no particle" in problems[0][1]

    def test_thousands_of_empty_bodies_are_named_in_a_few_lines(self):
        def change(s):
            s["bodies"] = [{"name": f"b{i}", "material": "rubber", "geometry": {
                "type": "sphere", "center": [-0.45 + 0.01 * (i % 90), -0.45 + 0.01 * (i // 90)], "radius": 0.001}}
                for i in range(900)]
        scene = load_scene(_changed(change))
        problems = empty_bodies(scene, summarize(scene).particles_per_body)
        assert len(problems) == 22 and problems[20] == ("bodies", "and 880 more bodies seed no particle")
        assert problems[21][0] == "bodies" and "nothing to simulate" in problems[21][1]

    def test_a_scene_without_particles_is_said_so(self):
        scene = load_scene(_changed(lambda s: s["grid"].update(cell_size=1e300)))
        paths = [path for path, _ in empty_bodies(scene, summarize(scene).particles_per_body)]
        assert paths == ["bodies[0]", "bodies[1]", "bodies"]


def _polygon_scene(vertices) -> dict:
    def change(s):
        s["bodies"] = [{**s["bodies"][0], "geometry": {"type": "polygon", "vertices": vertices}}]
    return _changed(change)


def _star(n: int) -> list[list[float]]:
    # spikes from near the centre to the rim: every edge overlaps half the others along both axes
    return [[(0.3 if i % 2 == 0 else 0.003) * math.cos(2 * math.pi * i / n),
             (0.3 if i % 2 == 0 else 0.003) * math.sin(2 * math.pi * i / n)] for i in range(n)]


class TestPolygons:
    def test_a_10000_vertex_star_is_refused_at_once(self):
        started = time.monotonic()
        errors = _errors(_polygon_scene(_star(10_000)))
        assert time.monotonic() - started < 3.0   # 10-40 ms idle; was 8-36 s (a loaded CI core gets room)
        assert errors[0]["path"] == "bodies[0].geometry.vertices" and "too complex" in errors[0]["message"]

    def test_a_10000_vertex_circle_crossing_itself_is_refused_fast(self):
        circle = [[0.3 * math.cos(2 * math.pi * i / 10_000), 0.3 * math.sin(2 * math.pi * i / 10_000)]
                  for i in range(10_000)]
        circle[10], circle[5000] = circle[5000], circle[10]
        started = time.monotonic()
        errors = _errors(_polygon_scene(circle))
        assert time.monotonic() - started < 3.0   # 10-40 ms idle; was 8-36 s (a loaded CI core gets room)
        assert "intersects itself" in errors[0]["message"]

    def test_the_pair_count_is_decided_before_any_pair_is_tested(self, monkeypatch):
        monkeypatch.setattr(geometry, "_segments_touch", lambda *a: pytest.fail("pairs were tested"))
        with pytest.raises(geometry.TooComplex):
            geometry.first_crossing(np.array(_star(4000)))

    def test_a_union_of_many_polygons_is_refused_at_the_one_past_the_cap(self, monkeypatch):
        triangle = [[0.0, 0.0], [0.01, 0.0], [0.0, 0.01]]
        checked = []
        real = geometry.first_crossing
        monkeypatch.setattr(geometry, "first_crossing", lambda v, *a, **k: checked.append(1) or real(v, *a, **k))

        def change(s):
            s["bodies"][0]["geometry"] = {"type": "union", "parts": [{"type": "polygon", "vertices": triangle}] * 4000}
        started = time.monotonic()
        errors = _errors(_changed(change))
        assert time.monotonic() - started < 3.0   # 4.6 s before the cap (a loaded machine)
        cap = geometry.MAX_POLYGONS
        assert [e["path"] for e in errors] == [f"bodies[0].geometry.parts[{cap}].vertices"]
        assert f"more than {cap} polygons" in errors[0]["message"]
        assert len(checked) == cap   # the polygons past the cap are not checked

    def test_the_vertices_of_all_polygons_are_capped_together(self):
        circle = [[0.01 * math.cos(2 * math.pi * i / 4000), 0.01 * math.sin(2 * math.pi * i / 4000)]
                  for i in range(4000)]

        def change(s):
            s["bodies"][0]["geometry"] = {"type": "union", "parts": [{"type": "polygon", "vertices": circle}] * 3}
        errors = _errors(_changed(change))
        assert [e["path"] for e in errors] == ["bodies[0].geometry.parts[2].vertices"]
        assert "12000 vertices" in errors[0]["message"]
