"""Whole job lifecycles over HTTP against the real stack: Redis, two Celery workers
running the real solver, the API under uvicorn."""
from __future__ import annotations

import io
import json
import os
import signal
import time

import h5py
import pytest

from service_support import (FINISHED, boxed, long_running, processes_with, two_disks, unstable,
                             wait_for_status, wait_until)

pytestmark = pytest.mark.usefixtures("no_jobs_left")

# The solver may end one time step past the end time (round-off in t += dt).
ONE_STEP = 1.001e-3


def submit(api, scene, **extra) -> dict:
    answer = api.post("/v1/jobs", json={"scene": scene, **extra})
    assert answer.status_code == 202, answer.text
    return answer.json()


def watch(api, job_id: str, timeout: float = 120) -> list[dict]:
    """Every record seen until the job finishes, polled fast."""
    seen = []
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        seen.append(api.get(f"/v1/jobs/{job_id}").json())
        if seen[-1]["status"] in FINISHED:
            return seen
        time.sleep(0.05)
    raise AssertionError(f"job {job_id} did not finish: {seen[-1]}")


def _cleanup(api, *job_ids):
    for job_id in job_ids:
        api.post(f"/v1/jobs/{job_id}/cancel")
        wait_for_status(api, job_id)
        api.delete(f"/v1/jobs/{job_id}")


def test_a_job_runs_to_success_with_progress_results_and_previews(api, stack):
    scene = boxed("lifecycle", end=20.0)  # about 20000 steps: a few progress updates
    job = submit(api, scene)
    assert job["status"] == "queued" and job["name"] == "lifecycle"
    assert job["summary"]["estimated_steps"] == 20000 and job["end_time"] == 20.0
    assert job["links"]["result"] == f"/v1/jobs/{job['id']}/result.h5"
    seen = watch(api, job["id"])
    statuses = [r["status"] for r in seen]
    assert statuses[-1] == "succeeded", seen[-1]
    assert "running" in statuses and statuses.index("running") < statuses.index("succeeded")
    assert "queued" not in statuses[statuses.index("running"):]

    running = [r for r in seen if r["status"] == "running" and r["step"] > 0]
    assert running, "no progress was reported while running"
    assert any(0 < r["progress"] < 1 for r in running)
    for record in running:
        assert 0 < record["progress"] <= 1
        assert record["sim_time"] == pytest.approx(record["progress"] * 20.0, rel=0.05)
        # the rate and the ETA are null until a recent rate is measured (solver/progress.py RateMeter)
        assert record["steps_per_second"] is None or record["steps_per_second"] > 0
        assert record["eta_seconds"] is None or record["eta_seconds"] >= 0
        assert record["energies"]["kinetic"] > 0
    steps = [r["step"] for r in running]
    assert steps == sorted(steps)

    final = seen[-1]
    assert final["progress"] == 1.0 and abs(final["step"] - 20000) <= 1
    assert final["sim_time"] == pytest.approx(20.0, abs=ONE_STEP)
    assert final["error"] is None and final["started_at"] <= final["finished_at"]

    result = api.get(f"/v1/jobs/{job['id']}/result.h5")
    assert result.status_code == 200 and result.headers["content-type"] == "application/x-hdf5"
    with h5py.File(io.BytesIO(result.content), "r") as h5:
        assert h5.attrs["status"] == "complete"
        assert len(h5["frames"]) == scene["output"]["frames"]
        assert json.loads(h5.attrs["scene"])["name"] == "lifecycle"

    series = api.get(f"/v1/jobs/{job['id']}/series").json()
    assert series["time"][-1] == pytest.approx(20.0, rel=1e-3)
    assert len(series["kinetic_energy"]) == len(series["time"]) > 10

    first = api.get(f"/v1/jobs/{job['id']}/preview.png", params={"frame": 0, "field": "velocity_magnitude"})
    assert first.status_code == 200 and first.headers["content-type"] == "image/png"
    assert first.content.startswith(b"\x89PNG")
    last = api.get(f"/v1/jobs/{job['id']}/preview.png")
    assert last.status_code == 200 and last.content != first.content
    again = api.get(f"/v1/jobs/{job['id']}/preview.png", params={"frame": 0, "field": "velocity_magnitude"})
    assert again.content == first.content
    assert (stack.data_dir / "jobs" / job["id"] / "previews" / "frame0_velocity_magnitude.png").is_file()
    bad = api.get(f"/v1/jobs/{job['id']}/preview.png", params={"frame": 99})
    assert bad.status_code == 422 and bad.json()["error"]["details"][0]["path"] == "frame"
    assert str(stack.data_dir) not in bad.text

    assert api.get(f"/v1/jobs/{job['id']}/scene").json()["name"] == "lifecycle"
    assert api.post(f"/v1/jobs/{job['id']}/cancel").status_code == 409

    # the worker logged the job's events as JSON lines with its id
    events = [json.loads(line) for log in (w.log for w in stack.workers)
              for line in log.read_text().splitlines() if line.startswith("{")]
    mine = [e["event"] for e in events if e.get("job_id") == job["id"]]
    assert "job started" in mine and "job succeeded" in mine


def test_a_running_job_is_cancelled_and_keeps_its_partial_result(api, stack):
    job = submit(api, long_running("to-cancel"))
    running = wait_for_status(api, job["id"], ("running",))
    wait_until_step = time.monotonic() + 30
    while api.get(f"/v1/jobs/{job['id']}").json()["step"] == 0 and time.monotonic() < wait_until_step:
        time.sleep(0.1)
    assert running["status"] == "running"

    asked = time.monotonic()
    answer = api.post(f"/v1/jobs/{job['id']}/cancel")
    assert answer.status_code == 202
    final = wait_for_status(api, job["id"], timeout=10)
    assert final["status"] == "cancelled" and time.monotonic() - asked < 5
    assert 0 < final["progress"] < 1

    # the solver process is gone: no `solver run` for this job is left
    assert not processes_with(job["id"])
    result = api.get(f"/v1/jobs/{job['id']}/result.h5")
    assert result.status_code == 200
    with h5py.File(io.BytesIO(result.content), "r") as h5:
        assert h5.attrs["status"] == "partial" and len(h5["frames"]) >= 1
    assert api.get(f"/v1/jobs/{job['id']}/preview.png").status_code == 200
    assert api.post(f"/v1/jobs/{job['id']}/cancel").status_code == 409


def test_a_queued_job_is_cancelled_at_once(api):
    # both workers busy: the third job waits in the queue
    busy = [submit(api, long_running(f"busy{i}")) for i in range(2)]
    queued = submit(api, two_disks("waiting"))
    for job in busy:
        wait_for_status(api, job["id"], ("running",))
    assert api.get(f"/v1/jobs/{queued['id']}").json()["status"] == "queued"
    answer = api.post(f"/v1/jobs/{queued['id']}/cancel")
    assert answer.status_code == 202 and answer.json()["status"] == "cancelled"
    # a job without a result answers 409 for its files
    result = api.get(f"/v1/jobs/{queued['id']}/result.h5")
    assert result.status_code == 409 and result.json()["error"]["code"] == "result_not_ready"
    _cleanup(api, *(job["id"] for job in busy))
    # when a worker gets to its message it skips it: the job stays cancelled
    time.sleep(1)
    assert api.get(f"/v1/jobs/{queued['id']}").json()["status"] == "cancelled"


def test_delete_removes_a_finished_job_and_its_files(api, stack):
    job = submit(api, two_disks("to-delete"))
    assert api.delete(f"/v1/jobs/{job['id']}").status_code in (409, 204)  # 409 while it runs
    wait_for_status(api, job["id"])
    folder = stack.data_dir / "jobs" / job["id"]
    assert (folder / "result.h5").is_file()
    assert api.delete(f"/v1/jobs/{job['id']}").status_code == 204
    assert api.get(f"/v1/jobs/{job['id']}").status_code == 404
    assert not folder.exists()
    assert job["id"] not in [j["id"] for j in api.get("/v1/jobs", params={"limit": 500}).json()["jobs"]]


def test_a_running_job_cannot_be_deleted(api):
    job = submit(api, long_running("not-deletable"))
    wait_for_status(api, job["id"], ("running",))
    answer = api.delete(f"/v1/jobs/{job['id']}")
    assert answer.status_code == 409 and answer.json()["error"]["code"] == "job_not_finished"
    _cleanup(api, job["id"])


def test_an_unstable_scene_fails_with_the_solver_diagnostic(api):
    job = submit(api, unstable())
    final = wait_for_status(api, job["id"])
    assert final["status"] == "failed"
    # the solver's diagnostic names the step, the particle and the quantity
    assert "unstable at step" in final["error"] and "particle" in final["error"]
    result = api.get(f"/v1/jobs/{job['id']}/result.h5")
    assert result.status_code == 200  # the frames written before it blew up
    with h5py.File(io.BytesIO(result.content), "r") as h5:
        assert h5.attrs["status"] == "partial"


def test_listing_filters_by_status_and_pages_newest_first(api):
    names = [f"page{i}" for i in range(5)]
    ids = [submit(api, two_disks(name, end=0.05))["id"] for name in names]
    for job_id in ids:
        wait_for_status(api, job_id)
    seen, cursor = [], None
    while True:
        params = {"limit": 2, **({"cursor": cursor} if cursor else {})}
        page = api.get("/v1/jobs", params=params).json()
        assert len(page["jobs"]) <= 2
        seen += [j["id"] for j in page["jobs"]]
        cursor = page["next_cursor"]
        if not cursor:
            break
    assert len(seen) == len(set(seen))
    mine = [job_id for job_id in seen if job_id in ids]
    assert mine == ids[::-1]  # newest first

    succeeded = api.get("/v1/jobs", params={"status": "succeeded", "limit": 500}).json()["jobs"]
    assert all(j["status"] == "succeeded" for j in succeeded)
    assert set(ids) <= {j["id"] for j in succeeded}
    assert api.get("/v1/jobs", params={"status": "running"}).json()["jobs"] == []
    for job_id in ids:
        api.delete(f"/v1/jobs/{job_id}")


def test_two_jobs_run_in_parallel_on_two_workers(api):
    jobs = [submit(api, boxed(f"parallel{i}", end=60.0)) for i in range(2)]
    records = [wait_for_status(api, job["id"], ("running",)) for job in jobs]
    # both running at the same time, on different workers
    both = [api.get(f"/v1/jobs/{job['id']}").json() for job in jobs]
    assert [r["status"] for r in both] == ["running", "running"]
    assert {r["worker"] for r in both} == {"w1@test", "w2@test"}
    finals = [wait_for_status(api, job["id"]) for job in jobs]
    assert [f["status"] for f in finals] == ["succeeded", "succeeded"]
    assert max(f["started_at"] for f in finals) < min(f["finished_at"] for f in finals)
    del records


def test_restarting_the_api_does_not_disturb_a_running_job(api, stack):
    job = submit(api, boxed("survives-restart", end=120.0))  # several seconds
    wait_for_status(api, job["id"], ("running",))
    assert stack.api.stop() == 0
    stack.start_api()
    record = api.get(f"/v1/jobs/{job['id']}").json()
    assert record["status"] in ("running", "succeeded")
    final = wait_for_status(api, job["id"])
    assert final["status"] == "succeeded" and final["attempts"] == 1
    assert final["sim_time"] == pytest.approx(120.0, abs=ONE_STEP)


def test_the_job_of_a_killed_worker_runs_again_on_the_other(api, stack):
    """A worker machine dies (SIGKILL): its solver stops with it, the job's lease expires
    (MPM_LEASE_SECONDS is 3 here) and the other worker runs the job again from the start."""
    job = submit(api, boxed("orphaned", end=40.0))
    record = wait_for_status(api, job["id"], ("running",))
    victim_name = record["worker"]
    victim = stack.workers[int(victim_name.split("@")[0][1:]) - 1]
    wait_until(lambda: processes_with(job["id"]), 30, "the solver of the job")
    [solver] = processes_with(job["id"])

    os.killpg(victim.popen.pid, signal.SIGKILL)
    victim.popen.wait()
    wait_until(lambda: solver not in processes_with(job["id"]), 15, "the orphaned solver to stop")
    try:
        final = wait_for_status(api, job["id"], timeout=120)
        assert final["status"] == "succeeded", final
        assert final["attempts"] == 2 and final["worker"] != victim_name
        assert final["sim_time"] == pytest.approx(40.0, abs=ONE_STEP)
    finally:
        stack.restart_worker(victim_name)


def test_the_two_disks_example_end_to_end_through_the_sdk(stack, tmp_path):
    """The README's path: the built-in example, submitted with the Python SDK over HTTP."""
    from mpm_client import Client
    from mpm_client.errors import JobFailed, ValidationFailed

    with Client(stack.url) as client:
        scene = client.example("two_disks")
        assert client.validate(scene).particles > 0
        job = client.submit(scene).wait(timeout=120, progress=False)
        assert job.record.status == "succeeded" and job.record.progress == 1.0
        path = job.download(tmp_path / "two_disks.h5")
        with h5py.File(path, "r") as h5:
            assert h5.attrs["status"] == "complete"
            assert len(h5["frames"]) == scene["output"]["frames"]
        job.preview(field="von_mises", path=tmp_path / "last.png")
        assert (tmp_path / "last.png").read_bytes().startswith(b"\x89PNG")
        assert len(job.series()["time"]) > 1
        assert job.id in [j.id for j in client.jobs(status="succeeded", limit=2)]

        with pytest.raises(JobFailed, match="unstable at step"):
            client.submit(unstable("sdk-unstable")).wait(timeout=120, progress=False)
        bad = two_disks()
        bad["bodies"][0]["geometry"]["radius"] = 0
        with pytest.raises(ValidationFailed) as failure:
            client.submit(bad)
        assert [e["path"] for e in failure.value.errors] == ["bodies[0].geometry.radius"]


def unpack_particles(body: bytes) -> tuple[dict, "np.ndarray", "np.ndarray"]:
    """The viewer's particle packing (docs/service.md): uint32 n, n bytes of JSON, float32 xyz, float32 values."""
    import numpy as np
    size = int.from_bytes(body[:4], "little")
    header = json.loads(body[4:4 + size])
    count = header["count"]
    xyz = np.frombuffer(body, "<f4", count * 3, 4 + size).reshape(count, 3)
    values = np.frombuffer(body, "<f4", count, 4 + size + 12 * count)
    assert len(body) == 4 + size + 16 * count
    return header, xyz, values


def test_frames_particles_and_animation_come_from_the_result(api):
    import numpy as np
    scene = two_disks("viewer", end=0.2)
    scene["output"] = {"frames": 5, "fields": ["position", "velocity", "stress"]}
    scene["units"] = {"length": "m", "time": "s", "mass": "kg", "stress": "Pa"}
    job = submit(api, scene)
    assert wait_for_status(api, job["id"])["status"] == "succeeded"
    result = api.get(f"/v1/jobs/{job['id']}/result.h5")
    with h5py.File(io.BytesIO(result.content), "r") as h5:
        names = sorted(h5["frames"])
        times = [float(h5["frames"][name].attrs["time"]) for name in names]
        position = h5["frames"][names[2]]["position"][()]
        speed = np.linalg.norm(h5["frames"][names[2]]["velocity"][()], axis=1)

    listing = api.get(f"/v1/jobs/{job['id']}/frames").json()
    assert [f["time"] for f in listing["frames"]] == times and [f["index"] for f in listing["frames"]] == [0, 1, 2, 3, 4]
    assert {"velocity_magnitude", "von_mises", "stress"} <= set(listing["fields"])
    assert listing["axes"] == ["x [m]", "y [m]"] and listing["time_unit"] == "s" and listing["dimension"] == 2

    answer = api.get(f"/v1/jobs/{job['id']}/frames/2/particles", params={"field": "velocity_magnitude"})
    assert answer.status_code == 200 and answer.headers["content-type"] == "application/octet-stream"
    header, xyz, values = unpack_particles(answer.content)
    assert (header["index"], header["time"], header["label"]) == (2, times[2], "velocity_magnitude [m/s]")
    # float32 of the stored float64: within its rounding, 2^-24 relative
    np.testing.assert_allclose(xyz[:, :2], position, rtol=2**-23)
    assert np.all(xyz[:, 2] == 0)
    np.testing.assert_allclose(values, speed, rtol=2**-23, atol=1e-30)
    # the colour range: the values' own (widened around them when they are all equal, as here)
    low, high = header["range"]
    assert low <= speed.min() <= speed.max() <= high and high > low
    bad = api.get(f"/v1/jobs/{job['id']}/frames/9/particles")
    assert bad.status_code == 422 and bad.json()["error"]["details"][0]["path"] == "frame"

    gif = api.get(f"/v1/jobs/{job['id']}/animation.gif", timeout=300)
    assert gif.status_code == 200 and gif.headers["content-type"] == "image/gif"
    from PIL import Image
    assert Image.open(io.BytesIO(gif.content)).n_frames == 5
    wrong = api.get(f"/v1/jobs/{job['id']}/animation.gif", params={"field": "nope"})
    assert wrong.status_code == 422 and wrong.json()["error"]["details"][0]["path"] == "field"


def test_a_failed_job_lists_the_frames_it_wrote(api):
    job = submit(api, unstable("viewer-unstable"))
    assert wait_for_status(api, job["id"])["status"] == "failed"
    frames = api.get(f"/v1/jobs/{job['id']}/frames").json()["frames"]
    with h5py.File(io.BytesIO(api.get(f"/v1/jobs/{job['id']}/result.h5").content), "r") as h5:
        stored = sorted(float(group.attrs["time"]) for group in h5["frames"].values())
    assert [f["time"] for f in frames] == stored and frames[-1]["time"] < 5.0
