"""The progress rate and ETA (solver/progress.py RateMeter): from a smoothed recent rate, shown once known."""
import io
import math

import pytest

from solver.progress import ProgressBar, RateMeter


def test_nothing_is_shown_before_a_measured_interval():
    meter = RateMeter()
    meter.update(now=10.0, step=3, sim_time=0.3)   # after start-up and compiling: only the origin
    assert meter.steps_per_second is None and meter.eta_seconds(1.0) is None


def test_the_start_up_does_not_enter_the_rate():
    meter = RateMeter()
    meter.update(now=30.0, step=1, sim_time=0.001)        # 30 s of compiling before the first step
    meter.update(now=30.5, step=501, sim_time=0.501)
    assert meter.steps_per_second == pytest.approx(1000.0)
    assert meter.eta_seconds(1.0) is None                 # 0.5 s measured: below MIN_SECONDS
    meter.update(now=31.0, step=1001, sim_time=1.001)
    assert meter.eta_seconds(2.0) == pytest.approx(2.0)   # 1 unit of simulated time per second


def test_a_change_of_rate_enters_with_the_weight_of_its_interval():
    meter = RateMeter()
    meter.update(0.0, 0, 0.0)
    meter.update(1.0, 100, 1.0)        # 100 steps/s
    meter.update(2.0, 300, 2.0)        # 200 steps/s over 1 s (an adaptive step that halved)
    weight = 1 - math.exp(-1.0 / RateMeter.TIME_CONSTANT)
    assert meter.steps_per_second == pytest.approx(100 + weight * 100)
    assert meter.eta_seconds(3.0) == pytest.approx(3.0)   # the simulated-time rate stayed 1 per second


def test_the_bar_leaves_out_an_unknown_rate_and_eta():
    bar = ProgressBar(io.StringIO())
    line = bar.format({"step": 2, "time": 0.1, "end_time": 1.0, "fraction": 0.1,
                       "steps_per_second": None, "eta_seconds": None})
    assert "steps/s" not in line and "ETA" not in line and "step 2" in line
