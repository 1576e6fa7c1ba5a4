"""Nothing lost: kill -9 the worker or its solver mid-job, kill -9 Redis with jobs
queued, restart the API mid-job; every job finishes, and a resumed job's result is
the result of an uninterrupted run, bit for bit (see tests/same_result.py)."""
from __future__ import annotations

import os
import signal
import time

import httpx

from fault_support import Serve, fault_env
from same_result import assert_same_result
from service.embedded_redis import EmbeddedRedis
from service_support import (FINISHED, MPM, Process, answers, boxed, free_port, processes_with,
                             wait_until)
from solver import run
from solver.checkpoint import CHECKPOINT_FILE


def resumable(name: str, end: float = 1.5) -> dict:
    """Thousands of steps, twenty frames, a checkpoint every 200 steps (however fast the
    machine: the tests freeze the solver once one is written, then inflict the fault)."""
    scene = boxed(name, end=end)
    scene["output"] = {"frames": 21, "fields": ["position", "velocity", "stress"],
                       "checkpoint": {"every_steps": 200}}
    return scene


def get_job(api: httpx.Client, job_id: str) -> dict | None:
    """The record, or None while the service answers 503 (Redis restarting)."""
    response = api.get(f"/v1/jobs/{job_id}")
    if response.status_code == 503:
        return None
    response.raise_for_status()
    return response.json()


def wait_finished(api: httpx.Client, job_id: str, timeout: float = 300) -> dict:
    return wait_until(lambda: (job := get_job(api, job_id)) and job["status"] in FINISHED and job,
                      timeout, f"job {job_id} finished", interval=0.2)


def submit(api: httpx.Client, scene: dict) -> str:
    response = api.post("/v1/jobs", json={"scene": scene})
    assert response.status_code == 202, response.text
    return response.json()["id"]


def solver_pid(job_id: str, other_than: int | None = None) -> int:
    def found():
        pids = [pid for pid in processes_with(job_id) if pid != other_than]
        return pids[0] if pids else None
    return wait_until(found, 60, f"the solver of job {job_id}", interval=0.02)


def freeze_after_checkpoint(serve: Serve, job_id: str) -> int:
    """SIGSTOP the job's solver once it has written a checkpoint: mid-way, whatever the
    machine's speed. Returns its pid."""
    pid = solver_pid(job_id)
    checkpoint = serve.job_dir(job_id) / CHECKPOINT_FILE
    wait_until(checkpoint.exists, 120, f"a checkpoint of job {job_id}", interval=0.01)
    os.kill(pid, signal.SIGSTOP)
    assert not (serve.job_dir(job_id) / "result.xdmf").exists(), "the job finished before the fault"
    return pid


def assert_same_as_uninterrupted(serve: Serve, job_id: str, tmp_path) -> None:
    folder = serve.job_dir(job_id)
    uninterrupted = run(folder / "scene.json", tmp_path / "uninterrupted")
    assert_same_result(uninterrupted.result_path, folder / "result.h5")
    assert not (folder / CHECKPOINT_FILE).exists()  # removed once the job is over


def test_worker_killed_mid_job_is_restarted_and_the_job_resumes_to_the_same_result(serve, api, tmp_path):
    job_id = submit(api, resumable("worker-killed"))
    solver = freeze_after_checkpoint(serve, job_id)
    worker = serve.children()["worker"]
    os.kill(worker, signal.SIGKILL)
    os.kill(solver, signal.SIGCONT)  # it has SIGTERM pending (its parent died): it stops

    job = wait_finished(api, job_id)
    assert job["status"] == "succeeded", job
    assert (job["attempts"], job["lost"]) == (2, 1)
    restarted = serve.children()["worker"]
    assert restarted != worker  # `mpm serve` started a new one
    log = serve.process.log.read_text(errors="replace")
    assert "job resumed from its checkpoint" in log and job_id in log
    assert_same_as_uninterrupted(serve, job_id, tmp_path)


def test_solver_killed_mid_job_is_resumed_by_its_worker(serve, api, tmp_path):
    job_id = submit(api, resumable("solver-killed"))
    os.kill(freeze_after_checkpoint(serve, job_id), signal.SIGKILL)

    job = wait_finished(api, job_id)
    assert job["status"] == "succeeded", job
    assert (job["attempts"], job["lost"]) == (1, 1)
    assert_same_as_uninterrupted(serve, job_id, tmp_path)


def test_a_job_that_keeps_crashing_is_failed_after_max_attempts(serve, api):
    job_id = submit(api, resumable("keeps-crashing", end=60.0))
    pid = None
    for _ in range(3):  # MPM_MAX_ATTEMPTS = 3
        pid = solver_pid(job_id, other_than=pid)
        os.kill(pid, signal.SIGKILL)
    job = wait_finished(api, job_id)
    assert job["status"] == "failed"
    assert "lost 3 times" in job["error"] and "killed by signal 9" in job["error"]
    assert "MPM_MAX_ATTEMPTS" in job["error"]
    assert not (serve.job_dir(job_id) / CHECKPOINT_FILE).exists()


def test_redis_killed_with_jobs_queued_loses_nothing(serve, api):
    """kill -9 of the embedded Redis: the API answers 503 until `mpm serve` has started it
    again (from its append-only file); every record and every queued job is still there."""
    ids = [submit(api, boxed(f"queued-{n}", end=1.0)) for n in range(4)]
    os.kill(serve.children()["redis"], signal.SIGKILL)
    statuses = []
    wait_until(lambda: statuses.append(api.get(f"/v1/jobs/{ids[-1]}").status_code) or statuses[-1] == 503,
               10, "a 503 while Redis is down", interval=0.02)
    unavailable = api.get("/v1/jobs")
    assert unavailable.status_code in (503, 200)  # 200 only if Redis is back already
    if unavailable.status_code == 503:
        assert unavailable.json()["error"]["code"] == "unavailable"
        assert unavailable.headers["retry-after"]
    wait_until(answers(serve.url, "/readyz"), 60, "ready again")
    for job_id in ids:
        job = wait_finished(api, job_id)
        assert job["status"] == "succeeded", job


def test_disk_quota_fails_a_job_cleanly_with_the_reason(serve, api):
    scene = resumable("too-big", end=20.0)
    scene["output"]["frames"] = 2000  # about 25 kB a frame: far over MPM_MAX_JOB_BYTES = 4 MiB
    job = wait_finished(api, submit(api, scene))
    assert job["status"] == "failed"
    assert "MPM_MAX_JOB_BYTES" in job["error"] and "4.0 MiB" in job["error"]
    # the frames written before the stop stay readable, as for any failed job
    assert api.get(f"/v1/jobs/{job['id']}/result.h5").status_code == 200


def test_api_restarted_mid_job_changes_nothing_for_the_job(tmp_path, tmp_path_factory):
    """The API keeps no state of its own: killed and started again while a job runs,
    the job goes on in its worker, unaware, and finishes."""
    data, logs = tmp_path / "data", tmp_path / "logs"
    logs.mkdir()
    with EmbeddedRedis(tmp_path / "redis") as redis_server:
        env = {**fault_env(data), "MPM_REDIS_URL": redis_server.url}
        port = free_port()
        url = f"http://127.0.0.1:{port}"
        worker = Process("worker", [*MPM, "worker", "--no-warmup"], env, logs).start()

        def start_api() -> Process:
            process = Process("api", [*MPM, "serve", "--no-worker", "--port", str(port)], env, logs).start()
            wait_until(answers(url, "/readyz"), 120, "the API ready", processes=(process, worker))
            return process

        api_process = start_api()
        try:
            with httpx.Client(base_url=url, timeout=30) as api:
                job_id = submit(api, resumable("api-restarted"))
                solver = solver_pid(job_id)
                os.kill(solver, signal.SIGSTOP)  # mid-job while the API is away, however fast it runs
                api_process.popen.kill()
                api_process.popen.wait()
                time.sleep(1.0)
                api_process = start_api()
                os.kill(solver, signal.SIGCONT)
                job = wait_finished(api, job_id)
            assert job["status"] == "succeeded", job
            assert (job["attempts"], job.get("lost", 0)) == (1, 0)
        finally:
            api_process.stop()
            worker.stop()
