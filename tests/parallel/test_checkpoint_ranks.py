"""A two-process run killed mid-way resumes from its checkpoint (issue 8 with issue 9).

Rank 0 writes the checkpoint from every process's particles; a resumed run reads it
on every process and splits the particles into slabs again. The slabs of the
resumed run are cut afresh, so ghost contributions are summed in another order than
in an uninterrupted run: the comparison is the equivalence test's (1e-12 relative
against one process), not bit for bit.
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time

import h5py
import numpy as np

from ranks import SCENE_2D, last_frame, relative_difference, run_cli, scene
from solver.checkpoint import CHECKPOINT_FILE
from solver.results import read_series

TOLERANCE = 1e-12
CASE = scene(SCENE_2D, time__end=0.4, output__frames=5, output__checkpoint={"every_steps": 20})


def _kill_after_first_checkpoint(out) -> int:
    """Start `mpm run -n 2`, freeze the whole process group once a checkpoint exists
    (so the kill lands mid-run however fast the machine is), then kill -9 it."""
    out.mkdir(parents=True, exist_ok=True)
    path = out / "scene.json"
    path.write_text(json.dumps(CASE))
    process = subprocess.Popen([sys.executable, "-m", "solver", "run", str(path), "-o", str(out), "-n", "2",
                                "--progress", "none"], start_new_session=True)
    deadline = time.monotonic() + 300
    while not (out / CHECKPOINT_FILE).exists():
        assert process.poll() is None, "the run ended before its first checkpoint"
        assert time.monotonic() < deadline
        time.sleep(0.002)
    os.killpg(process.pid, signal.SIGSTOP)
    os.killpg(process.pid, signal.SIGKILL)
    process.wait(timeout=30)
    with h5py.File(out / CHECKPOINT_FILE, "r") as h5:
        return int(h5.attrs["step"])


def test_a_killed_two_process_run_resumes_from_its_checkpoint(tmp_path):
    reference = tmp_path / "k1"
    assert run_cli(CASE, reference, 1).returncode == 0

    out = tmp_path / "k2"
    step = _kill_after_first_checkpoint(out)
    assert 0 < step < 400
    resumed = subprocess.run([sys.executable, "-m", "solver", "run", "--resume", str(out), "-n", "2",
                              "--progress", "none"], capture_output=True, text=True, timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    assert not (out / CHECKPOINT_FILE).exists()   # a finished run removes it

    want, got = last_frame(reference), last_frame(out)
    assert got["step"] == want["step"] == 400
    assert np.array_equal(got["fields"]["id"], want["fields"]["id"])
    for field in ("position", "velocity", "stress"):
        assert relative_difference(want["fields"][field], got["fields"][field]) <= TOLERANCE, field
    # the work terms go on from the checkpoint's totals, summed over the processes that wrote it
    want_series, got_series = read_series(reference / "result.h5"), read_series(out / "result.h5")
    assert np.array_equal(got_series["time"], want_series["time"])
    assert np.max(np.abs(want_series["external_work"])) > 1e-3   # gravity did work
    for name in ("external_work", "boundary_work", "kinetic_energy", "energy_error"):
        scale = np.max(np.abs(want_series["total_energy"]))
        assert np.max(np.abs(got_series[name] - want_series[name])) <= 1e-9 * scale, name

