"""Jobs on two MPI processes through the whole stack (issue 9): the worker starts the
ranks (`mpm run -n 2` -> mpiexec), reports rank 0's progress, and a cancel stops them all."""
from __future__ import annotations

import io
import time

import h5py
import numpy as np
import pytest

from service_support import long_running, processes_with, two_disks, wait_for_status

pytestmark = pytest.mark.usefixtures("no_jobs_left")


def submit(api, scene, processes):
    answer = api.post("/v1/jobs", json={"scene": scene, "processes": processes})
    assert answer.status_code == 202, answer.text
    return answer.json()


def last_frame(api, job_id):
    answer = api.get(f"/v1/jobs/{job_id}/result.h5")
    assert answer.status_code == 200
    with h5py.File(io.BytesIO(answer.content), "r") as h5:
        frame = h5["frames"][sorted(h5["frames"])[-1]]
        return {key: frame[key][()] for key in frame}


def test_a_two_process_job_gives_the_single_process_answer(api, stack):
    # The two disks, 5x faster: they meet after about 150 of the 300 steps, where the
    # cut between the 2 slabs lies, and collide across it. Ghost sums in another
    # order: round-off only (1e-12, as tests/parallel/test_equivalence.py derives).
    scene = two_disks("two-processes", end=0.3)
    scene["bodies"][0]["geometry"]["center"] = [-0.18, -0.18]
    scene["bodies"][1]["geometry"]["center"] = [0.18, 0.18]
    scene["bodies"][0]["initial_velocity"] = [0.5, 0.5]
    scene["bodies"][1]["initial_velocity"] = [-0.5, -0.5]
    one, two = submit(api, scene, 1), submit(api, scene, 2)
    assert one["processes"] == 1 and two["processes"] == 2
    for job in (one, two):
        final = wait_for_status(api, job["id"], timeout=180)
        assert final["status"] == "succeeded", final
    a, b = last_frame(api, one["id"]), last_frame(api, two["id"])
    assert np.array_equal(a["id"], b["id"])
    assert np.max(np.abs(a["stress"])) > 1.0   # they did collide (stresses of order rho c v ~ 100 Pa)
    for field in ("position", "velocity", "stress"):
        assert np.max(np.abs(a[field] - b[field])) <= 1e-12 * np.max(np.abs(a[field])), field


def test_cancelling_a_two_process_job_stops_every_rank(api, stack):
    job = submit(api, long_running("two-process-cancel"), 2)
    wait_for_status(api, job["id"], ("running",))
    deadline = time.monotonic() + 120
    while api.get(f"/v1/jobs/{job['id']}").json()["step"] == 0 and time.monotonic() < deadline:
        time.sleep(0.1)
    # rank 0 reported steps: every rank is in the time loop, where a stop ends the run cleanly
    assert api.get(f"/v1/jobs/{job['id']}").json()["step"] > 0
    # mpiexec (the exec'd `mpm run -n 2`) and its two ranks, each with the job's scene path
    assert len(processes_with(job["id"])) >= 3

    assert api.post(f"/v1/jobs/{job['id']}/cancel").status_code == 202
    final = wait_for_status(api, job["id"], timeout=20)
    assert final["status"] == "cancelled"
    deadline = time.monotonic() + 10
    while processes_with(job["id"]) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert not processes_with(job["id"])
    with h5py.File(io.BytesIO(api.get(f"/v1/jobs/{job['id']}/result.h5").content), "r") as h5:
        assert h5.attrs["status"] == "partial" and len(h5["frames"]) >= 1
