"""The SDK and the `mpm` client commands against a real service (`mpm serve`: API,
embedded Redis and a worker), covering the whole surface and its error mapping."""
from __future__ import annotations

import asyncio
import json
import socket
import subprocess
import sys
import time
import uuid
from pathlib import Path

import h5py
import numpy as np
import pytest

import live_scenes
from mpm_client import AsyncClient, Client, errors

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def example(live) -> dict:
    with Client(live.url) as client:
        return client.example(live_scenes.EXAMPLE)


def wait_running(job, timeout: float = 60.0) -> None:
    """Until the job has made some progress (its first frame is written by then)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        record = job.refresh().record
        if record.status == "running" and record.step > 0:
            return
        assert record.status in ("queued", "running"), record
        time.sleep(0.2)
    raise AssertionError(f"job {job.id} did not start running within {timeout} s: {job.record}")


def test_examples_and_validation_summary(live_client, example):
    names = [e.name for e in live_client.examples()]
    assert live_scenes.EXAMPLE in names
    summary = live_client.validate(live_scenes.quick(example))
    assert summary.particles > 0 and summary.grid_nodes > 0
    assert summary.estimated_steps == round(example["time"]["end"] / example["time"]["dt"])


def test_validation_errors_name_every_path_and_create_no_job(live_client, example):
    scene = live_scenes.invalid(example)
    material = next(iter(scene["materials"]))
    expected = {"bodies[0].geometry.radius", f"materials.{material}.poisson_ratio"}
    with pytest.raises(errors.ValidationFailed) as caught:
        live_client.validate(scene)
    assert {e["path"] for e in caught.value.errors} == expected
    assert all(e["message"] for e in caught.value.errors)

    before = [job.id for job in live_client.jobs()]
    with pytest.raises(errors.ValidationFailed) as caught:
        live_client.submit(scene)
    assert {e["path"] for e in caught.value.errors} == expected
    assert [job.id for job in live_client.jobs()] == before  # a rejected job never half-exists


def test_a_multi_frame_result_round_trip(live_client, example, tmp_path):
    scene = live_scenes.quick(example, frames=6)
    job = live_client.submit(scene)
    assert job.record.status in ("queued", "running")
    assert job.wait(timeout=180, poll=0.2, progress=False) is job
    record = job.record
    assert (record.status, record.progress, record.error) == ("succeeded", 1.0, None)
    assert record.sim_time == pytest.approx(scene["time"]["end"], rel=1e-6)
    assert job.scene()["name"] == "sdk-quick"

    path = job.download(tmp_path / "nested" / "result.h5")
    assert sorted(p.name for p in path.parent.iterdir()) == ["result.h5"]  # no leftovers
    with h5py.File(path, "r") as result:
        assert result.attrs["format"] == "mpm-result" and result.attrs["status"] == "complete"
        frames = sorted(result["frames"])
        assert len(frames) == 6
        times = [result["frames"][f].attrs["time"] for f in frames]
        assert times[0] == 0.0 and times[-1] == pytest.approx(scene["time"]["end"], rel=1e-6)
        ids = [np.sort(result["frames"][f]["id"][()]) for f in frames]
        assert all(np.array_equal(ids[0], other) for other in ids[1:])  # the same particles in every frame
        assert len(ids[0]) == record.summary.particles
        kinetic = result["time_series"]["kinetic_energy"][()]

    with job.open() as reopened:  # reuses the download
        assert sorted(reopened["frames"]) == frames

    series = job.series()
    assert {"time", "kinetic_energy", "strain_energy", "total_energy"} <= set(series)
    assert np.all(np.diff(series["time"]) > 0)
    np.testing.assert_array_equal(series["kinetic_energy"], kinetic)

    last = job.preview(path=tmp_path / "last.png")
    first = job.preview(frame=0, field="von_mises")
    assert last.startswith(PNG_SIGNATURE) and first.startswith(PNG_SIGNATURE) and first != last
    assert (tmp_path / "last.png").read_bytes() == last
    with pytest.raises(errors.ValidationFailed) as caught:
        job.preview(frame=99)
    assert caught.value.errors[0]["path"] == "frame"

    job.delete()
    with pytest.raises(errors.NotFound):
        job.refresh()


def test_jobs_are_listed_newest_first_over_pages_and_filtered(live_client, example):
    submitted = [live_client.submit(live_scenes.quick(example, f"sdk-list-{i}")) for i in range(3)]
    for job in submitted:
        job.wait(timeout=180, poll=0.2, progress=False)
    listed = list(live_client.jobs(limit=1))  # one job a page: the iterator follows the cursors
    ids = [job.id for job in listed]
    assert len(ids) == len(set(ids))
    positions = [ids.index(job.id) for job in submitted]
    assert positions == sorted(positions, reverse=True)  # the later submitted, the earlier listed
    created = [job.record.created_at for job in listed]
    assert created == sorted(created, reverse=True)
    succeeded = list(live_client.jobs(status="succeeded"))
    assert {job.id for job in submitted} <= {job.id for job in succeeded}
    assert all(job.record.status == "succeeded" for job in succeeded)


def test_cancel_a_running_job_keeps_its_partial_result(live_client, example, tmp_path):
    job = live_client.submit(live_scenes.long(example))
    wait_running(job)
    with pytest.raises(errors.Conflict):
        job.delete()  # not finished yet
    with pytest.raises(errors.Conflict):
        job.download(tmp_path / "early.h5")
    assert not (tmp_path / "early.h5").exists()

    job.cancel()
    with pytest.raises(errors.JobCancelled):
        job.wait(timeout=60, poll=0.2, progress=False)
    assert job.record.status == "cancelled" and job.record.progress < 1.0
    with pytest.raises(errors.Conflict):
        job.cancel()  # already finished

    with h5py.File(job.download(tmp_path / "partial.h5"), "r") as result:
        assert result.attrs["status"] == "partial"
        assert len(result["frames"]) >= 1
    job.delete()
    with pytest.raises(errors.NotFound):
        live_client.job(job.id)


def test_a_blown_up_run_raises_job_failed_with_the_solver_diagnostic(live_client, example):
    job = live_client.submit(live_scenes.unstable(example))
    with pytest.raises(errors.JobFailed) as caught:
        job.wait(timeout=120, poll=0.2, progress=False)
    assert caught.value.status == "failed"
    assert "unstable" in caught.value.diagnostic and "particle" in caught.value.diagnostic
    assert job.record.error == caught.value.diagnostic


def test_unknown_job_and_oversized_request_are_typed(live_client, example):
    with pytest.raises(errors.NotFound):
        live_client.job(str(uuid.uuid4()))
    scene = live_scenes.quick(example)
    scene["name"] = "x" * 300_000  # over the service's MPM_MAX_BODY_BYTES
    with pytest.raises(errors.TooLarge):
        live_client.submit(scene)


def test_a_closed_port_is_service_unavailable():
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]  # nothing listens once the probe is closed
    with Client(f"http://127.0.0.1:{port}", retries=1, backoff=0.01) as client:
        with pytest.raises(errors.ServiceUnavailable, match=f"cannot reach the service at http://127.0.0.1:{port}"):
            client.examples()
    unreachable = mpm("jobs", "--server", f"http://127.0.0.1:{port}")
    assert unreachable.returncode == 1 and f"http://127.0.0.1:{port}" in unreachable.stderr


def test_async_client_live(live, example, tmp_path):
    async def scenario() -> tuple[str, dict, bytes]:
        async with AsyncClient(live.url) as client:
            job = await client.submit(live_scenes.quick(example, "sdk-async"))
            await job.wait(timeout=180, poll=0.2, progress=False)
            await job.download(tmp_path / "async.h5")
            series = await job.series()
            png = await job.preview()
            listed = [j.id async for j in client.jobs(limit=2)]
            assert job.id in listed
            await job.delete()
            return job.record.status, series, png

    status, series, png = asyncio.run(scenario())
    assert status == "succeeded"
    assert series["time"][-1] == pytest.approx(example["time"]["end"], rel=1e-6)
    assert png.startswith(PNG_SIGNATURE)
    with h5py.File(tmp_path / "async.h5", "r") as result:
        assert len(result["frames"]) == 6


def mpm(*args: str, env_server: str | None = None) -> subprocess.CompletedProcess:
    """The installed `mpm` script, as a user runs it."""
    env = {"PATH": "/usr/bin:/bin", "HOME": str(Path.home())}
    if env_server:
        env["MPM_SERVER"] = env_server
    return subprocess.run([str(Path(sys.executable).with_name("mpm")), *args], capture_output=True,
                          text=True, timeout=300, env=env)


def test_the_mpm_client_commands(live, example, tmp_path):
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps(live_scenes.quick(example, "sdk-cli")))
    out = tmp_path / "cli.h5"

    submitted = mpm("submit", str(scene), "--download", str(out), "--server", live.url)
    assert submitted.returncode == 0, submitted.stderr
    job_id = submitted.stdout.strip()
    assert "succeeded" in submitted.stderr  # the progress lines
    with h5py.File(out, "r") as result:
        assert len(result["frames"]) == 6

    listed = mpm("jobs", "--status", "succeeded", env_server=live.url)  # the server from MPM_SERVER
    assert listed.returncode == 0, listed.stderr
    assert any(line.split()[0] == job_id[:8] and "sdk-cli" in line for line in listed.stdout.splitlines())

    status = mpm("status", job_id, "--json", "--server", live.url)
    assert status.returncode == 0 and json.loads(status.stdout)["status"] == "succeeded"

    again = tmp_path / "again.h5"
    downloaded = mpm("download", job_id, str(again), "--server", live.url)
    assert downloaded.returncode == 0 and again.read_bytes() == out.read_bytes()

    refused = mpm("cancel", job_id, "--server", live.url)
    assert refused.returncode == 1 and "mpm cancel: error:" in refused.stderr

    missing = mpm("status", str(uuid.uuid4()), "--server", live.url)
    assert missing.returncode == 1 and "error" in missing.stderr


YOUNG = "/materials/elastic/youngs_modulus"


def test_a_sweep_from_the_sdk_waits_and_tables(live_client, example, capsys):
    scene = live_scenes.quick(example, "sdk-sweep")
    scene["time"]["end"] = 0.2
    sweep = live_client.sweep(scene, {YOUNG: [1000, 4000], "/time/end": [0.1, 0.2]}, mode="zip")
    assert [job["parameters"] for job in sweep.jobs] == [{YOUNG: 1000, "/time/end": 0.1},
                                                         {YOUNG: 4000, "/time/end": 0.2}]
    sweep.wait(progress=True, timeout=300)
    assert f"sweep {sweep.id[:8]}: 2/2 finished" in capsys.readouterr().err
    assert sweep.record["counts"]["succeeded"] == 2
    rows = sweep.table().splitlines()
    assert rows[0].split() == ["ID", YOUNG, "/time/end", "STATUS", "KINETIC", "STRAIN", "TOTAL"]
    for row, job in zip(rows[1:], sweep.jobs):
        cells = row.split()
        assert cells[:4] == [job["id"][:8], str(job["parameters"][YOUNG]), str(job["parameters"]["/time/end"]),
                             "succeeded"]
        assert float(cells[6]) == pytest.approx(job["energies"]["total"], rel=1e-5)
    assert sweep.id in [s.id for s in live_client.sweeps()]
    with pytest.raises(errors.ValidationFailed) as caught:
        live_client.sweep(scene, {YOUNG: [1000, 0]})
    assert caught.value.errors[0]["path"] == f"parameters.{YOUNG}"
    sweep.delete()
    with pytest.raises(errors.NotFound):
        live_client.get_sweep(sweep.id)


def test_the_sweep_delete_and_log_commands(live, example, tmp_path):
    scene = tmp_path / "scene.json"
    quick = live_scenes.quick(example, "cli-sweep")
    quick["time"]["end"] = 0.1
    scene.write_text(json.dumps(quick))
    swept = mpm("sweep", str(scene), "-p", f"{YOUNG}=1000,2000", "--wait", "-q", "--server", live.url)
    assert swept.returncode == 0, swept.stderr
    sweep_id, header, *rows = swept.stdout.splitlines()
    assert header.split()[:3] == ["ID", YOUNG, "STATUS"]
    assert [row.split()[1:3] for row in rows] == [["1000", "succeeded"], ["2000", "succeeded"]]
    short = rows[0].split()[0]  # 8 characters, as `mpm jobs` shows them

    log = mpm("log", short, "--server", live.url)
    assert log.returncode == 0, log.stderr
    assert json.loads(log.stdout.splitlines()[-1])["event"] == "done"  # the solver's last line
    follow = mpm("log", short, "--follow", "--since", "0", "--server", live.url)  # a finished job: returns
    assert follow.returncode == 0 and follow.stdout == log.stdout

    bad = mpm("sweep", str(scene), "-p", "youngs=1", "--server", live.url)
    assert bad.returncode == 2 and "POINTER=V1,V2" in bad.stderr
    assert mpm("delete", short, "--server", live.url).returncode == 0
    gone = mpm("status", short, "--server", live.url)
    assert gone.returncode == 1 and f"no job '{short}'" in gone.stderr
    assert mpm("delete", "zz", "--server", live.url).returncode == 1
    with Client(live.url) as client:
        client.get_sweep(sweep_id).delete()


def test_a_prefix_shared_by_two_jobs_is_refused(live_client, example):
    jobs = []
    for i in range(17):  # 17 ids, 16 hex digits: two start alike (each cancelled at once: the queue quota)
        jobs.append(live_client.submit(live_scenes.long(example, f"prefix{i}")))
        jobs[-1].cancel()
    shared = next(c for c in "0123456789abcdef" if sum(job.id.startswith(c) for job in jobs) > 1)
    with pytest.raises(ValueError, match="several jobs"):
        live_client.job(shared)
    unique = next(job for job in jobs if sum(other.id.startswith(job.id[:8]) for other in jobs) == 1)
    assert live_client.job(unique.id[:8]).id == unique.id
