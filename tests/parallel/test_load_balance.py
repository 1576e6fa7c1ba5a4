"""Load balance (issue 9): slab boundaries follow the particles.

A block starts entirely in the left half of a long grid and travels right. With
even slabs that never move (rebalance_every = 0) the first process holds every
particle at the start; with rebalancing every 10 steps the two processes end
within 10% of each other. The cuts move by whole cell layers; a layer of this
block holds 1/30 of its particles, so the best cut is off by at most half a
layer (1.7% of the particles), well inside the 10% the issue asks for.
"""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from solver.parallel import launch

STEPS = 100
SCENE = {
    "name": "load-balance", "dimension": 2,
    "grid": {"lower": [0.0, 0.0], "upper": [2.0, 0.5], "cell_size": 0.02},
    "materials": {"steel": {"model": "linear_elastic", "density": 1000, "youngs_modulus": 1000,
                            "poisson_ratio": 0.3}},
    "bodies": [{"name": "block", "material": "steel", "particles_per_cell": 2, "initial_velocity": [4.0, 0.0],
                "geometry": {"type": "box", "lower": [0.1, 0.1], "upper": [0.7, 0.4]}}],
    "time": {"end": 0.1, "dt": 0.001},
}


def counts(tmp_path: Path, rebalance_every: int, scene: dict = SCENE, *slow_rank_zero: str) -> dict:
    scene = {**scene, "parallel": {"processes": 2, "rebalance_every": rebalance_every, **scene.get("parallel", {})}}
    path = tmp_path / f"scene-{rebalance_every}-{scene['parallel'].get('balance', '')}.json"
    path.write_text(json.dumps(scene))
    probe = Path(__file__).with_name("rank_counts.py")
    command = launch.python(2, str(probe), str(path), str(STEPS), *slow_rank_zero)
    finished = subprocess.run(command, capture_output=True, text=True, timeout=300, env=launch.environment())
    assert finished.returncode == 0, finished.stderr
    return json.loads(finished.stdout.strip().splitlines()[-1])


def test_rebalancing_keeps_per_process_counts_within_ten_percent(tmp_path):
    fixed = counts(tmp_path, 0)
    assert fixed["cuts_start"] == fixed["cuts_end"] == [0, 50, 100]
    assert min(fixed["counts"]) < 0.5 * max(fixed["counts"])   # even slabs: far from balanced

    balanced = counts(tmp_path, 10)
    assert sum(balanced["counts"]) == sum(fixed["counts"])
    assert balanced["cuts_end"][1] > balanced["cuts_start"][1]   # the cut followed the block
    low, high = min(balanced["counts"]), max(balanced["counts"])
    assert (high - low) / high <= 0.10, balanced


# A still block over the whole grid: even slabs hold even counts.
STILL = {**SCENE, "bodies": [{**SCENE["bodies"][0], "initial_velocity": [0.0, 0.0],
                              "geometry": {"type": "box", "lower": [0.1, 0.1], "upper": [1.9, 0.4]}}]}


def test_balancing_the_work_gives_a_slower_process_fewer_particles(tmp_path):
    """Rank 0 sleeps 5 us per particle it holds each step (a work per particle about ten times
    the step's): balanced by particles the two keep even counts; balanced by measured work the
    cut moves until rank 0's sleep and rank 1's stepping take about as long, so rank 0 ends
    with a small share (its particles times 5 us against rank 1's times its own cost)."""
    delay = "5e-6"
    by_particles = counts(tmp_path, 10, STILL, delay)
    low, high = sorted(by_particles["counts"])
    assert (high - low) / high <= 0.10, by_particles
    by_work = counts(tmp_path, 10, {**STILL, "parallel": {"balance": "work"}}, delay)
    slow, fast = by_work["counts"]
    assert slow + fast == sum(by_particles["counts"])
    assert slow < 0.5 * fast, by_work
    assert by_work["cuts_end"][1] < by_particles["cuts_end"][1]
