"""Validation refuses a fixed time step above the scene's stability limit (solver/stability.py)."""
import math

import pytest

from solver import stability
from solver.examples import load_example
from solver.scene import SceneError
from solver.scene_checks import load_scene


def two_disks(dt: float, **time) -> dict:
    scene = load_example("two_disks")
    scene["time"] = {**scene["time"], "dt": dt, **time}
    scene["output"]["frames"] = 11   # a frame a step at most: 3.5 / 0.2 is 18 steps (the example has 71 frames)
    return scene


# E2: c = sqrt((lambda + 2 mu) / rho) = 1.1602 for E = 1000, nu = 0.3, rho = 1000; the disks move at
# 0.1 sqrt(2); h = 0.05, so the limit is 0.05 / (c + 0.1 sqrt(2))
C = math.sqrt((7500 / 13 + 2 * 5000 / 13) / 1000)
LIMIT = 0.05 / (C + 0.1 * math.sqrt(2))


def test_a_step_four_times_the_limit_is_refused_naming_time_dt_and_the_limit():
    with pytest.raises(SceneError) as caught:
        load_scene(two_disks(0.2))
    (error,) = caught.value.errors
    assert error["path"] == "time.dt"
    assert f"{LIMIT:.6g}" in error["message"] and "allow_unstable_dt" in error["message"]


def test_the_limit_is_the_wave_limit_and_a_step_below_it_passes():
    assert stability.stable_limit(load_scene(two_disks(0.001))).dt == pytest.approx(LIMIT, rel=1e-12)
    load_scene(two_disks(0.99 * LIMIT))
    with pytest.raises(SceneError):
        load_scene(two_disks(1.01 * LIMIT))


def test_a_scene_that_says_it_knows_may_run_above_the_limit():
    scene = load_scene(two_disks(0.2, allow_unstable_dt=True))
    assert scene.time.dt == 0.2


def test_another_limit_joins_the_smallest_wins(monkeypatch):
    monkeypatch.setattr(stability, "LIMITS", stability.LIMITS + [lambda scene: stability.Limit(1e-3, "conduction")])
    with pytest.raises(SceneError) as caught:
        load_scene(two_disks(0.002))
    assert "1e-3" in caught.value.errors[0]["message"].replace("0.001", "1e-3")
    assert "conduction" in caught.value.errors[0]["message"]
