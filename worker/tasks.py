"""The one Celery task: run one job from its record to a finished status.

The task is idempotent and safe to redeliver. A finished or deleted job is
skipped; a lease in Redis makes sure only one worker runs a job at a time (a
copy redelivered while the first run is alive finds the lease taken); a job
found `running` with a free lease was lost with its worker and runs again. When
the worker shuts down the job goes back to the queue.

Nothing is lost: the solver writes restart checkpoints into the job's folder, and a
job run again (after its worker or its solver process was killed, or a shutdown)
goes on from the last one. A job whose run was lost `MPM_MAX_ATTEMPTS` times is
failed with the reason; a job whose results outgrow the disk limits is failed too.
"""
from __future__ import annotations

import logging
import os
import shutil
import threading
import time
import uuid
from functools import lru_cache
from typing import Any

import redis
from celery import shared_task
from celery.exceptions import Reject
from celery.signals import worker_shutting_down

from core.celery_app import TASK_NAME
from core.paths import JobFiles, parse_job_id
from core.settings import Settings, get_settings
from core.models import ACTIVE, FINISHED, now_iso
from core.store import JobStore
from solver.checkpoint import checkpoint_path
from worker.disk import DiskQuota
from worker.launcher import launcher_for
from worker.runner import Outcome, RunControl

log = logging.getLogger("mpm.worker")

# Keys of the solver's progress line -> fields of the job record.
PROGRESS_FIELDS = {"fraction": "progress", "step": "step", "time": "sim_time",
                   "end_time": "end_time", "steps_per_second": "steps_per_second",
                   "eta_seconds": "eta_seconds", "energies": "energies", "dt": "dt", "stage": "stage"}

# Set when the worker begins a shutdown: running jobs stop and go back to the queue.
_shutting_down = threading.Event()


@worker_shutting_down.connect
def _on_shutdown(**_: Any) -> None:
    _shutting_down.set()


@lru_cache
def get_store() -> JobStore:
    client = redis.Redis.from_url(get_settings().redis_url, decode_responses=True,
                                  health_check_interval=30)
    return JobStore(client)


@shared_task(name=TASK_NAME, bind=True)
def run_job(self, job_id: str) -> None:
    job_id = parse_job_id(job_id)
    store = get_store()
    worker = self.request.hostname or "worker"
    # Redis going away while a job is taken is waited out, not raised: a raised error would
    # acknowledge the message and leave the job queued with nothing on the queue.
    job = _retry_redis(lambda: store.get(job_id))
    if job is None or job["status"] in FINISHED:
        log.info("job skipped: finished or deleted", extra={"job_id": job_id})
        # cancelled while back on the queue: a Slurm job left running by a stopped worker is ended
        launcher_for(get_settings()).stop_leftover(JobFiles(get_settings().jobs_dir, job_id))
        return
    token = f"{worker}:{uuid.uuid4()}"
    if not _retry_redis(lambda: store.acquire_lease(job_id, token, get_settings().lease_seconds)):
        log.warning("job skipped: another worker holds it", extra={"job_id": job_id})
        return
    try:
        _run_leased(store, job_id, job, worker, token)
    finally:
        try:
            store.release_lease(job_id, token)
        except redis.RedisError as exc:  # it expires by itself within MPM_LEASE_SECONDS
            log.warning("lease not released: %s", exc, extra={"job_id": job_id})


def _run_leased(store: JobStore, job_id: str, job: dict[str, Any], worker: str, token: str) -> None:
    settings = get_settings()
    files = JobFiles(settings.jobs_dir, job_id)
    # Found running with a free lease: its worker was lost (the sweep of the heartbeat
    # counts the ones it puts back on the queue itself).
    lost = job.get("lost", 0) + (job["status"] == "running")
    if lost >= settings.max_attempts:
        _give_up(store, job_id, files, lost, "its worker was lost")
        return
    before = _retry_redis(lambda: store.transition(
        job_id, ACTIVE, "running", started_at=now_iso(), worker=worker,
        attempts=job.get("attempts", 0) + 1, lost=lost, steps_per_second=None, eta_seconds=None, stage="compiling",
        error=None))
    if before not in ACTIVE:
        log.info("job skipped: it is %s", before, extra={"job_id": job_id})
        return
    if before == "running":
        log.warning("job restarted: its worker was lost", extra={"job_id": job_id})
    resuming = checkpoint_path(files.dir).exists()
    launcher = launcher_for(settings)   # local, or Slurm (MPM_LAUNCHER)
    if not resuming and not launcher.in_flight(files):   # (a Slurm job still writing there is followed)
        _clear_outputs(files)
    if _retry_redis(lambda: store.cancel_requested(job_id)):
        launcher.stop_leftover(files)
        _retry_redis(lambda: store.transition(job_id, ["running"], "cancelled", finished_at=now_iso()))
        return
    log.info("job resumed from its checkpoint" if resuming else "job started",
             extra={"job_id": job_id, "worker": worker})
    quota = DiskQuota(settings.jobs_dir, files.dir, settings.max_job_bytes, settings.max_total_bytes)

    lease_renewed = time.monotonic()

    # A Redis hiccup must not end a long run: the checks and updates below skip a beat
    # instead. If Redis stays away longer than the lease, another worker takes the job
    # over, and this run stops when it finds its lease gone.
    def should_stop() -> str | None:
        nonlocal lease_renewed
        try:  # first: it is also what keeps the lease while a stop's grace runs
            if time.monotonic() - lease_renewed > settings.lease_seconds / 6:
                if not store.renew_lease(job_id, token, settings.lease_seconds):
                    return "lease_lost"
                lease_renewed = time.monotonic()
        except redis.RedisError as exc:
            log.warning("redis unavailable: %s", exc, extra={"job_id": job_id})
        if _shutting_down.is_set():
            return "shutdown"
        if quota.check() is not None:
            return "disk_quota"
        try:
            if store.cancel_requested(job_id):
                return "cancelled"
        except redis.RedisError as exc:
            log.warning("redis unavailable: %s", exc, extra={"job_id": job_id})
        return None

    def on_progress(line: dict[str, Any]) -> None:
        fields = {PROGRESS_FIELDS[k]: v for k, v in line.items() if k in PROGRESS_FIELDS}
        try:
            store.update_running(job_id, **fields)
        except redis.RedisError as exc:
            log.warning("progress not recorded: %s", exc, extra={"job_id": job_id})

    while True:
        outcome = launcher.run(
            job_id, files, job.get("processes", 1), job.get("nodes") or 1,
            RunControl(on_progress=on_progress, should_stop=should_stop, progress_interval=settings.progress_interval,
                       timeout_seconds=settings.max_job_seconds, env=job_environment(settings)))
        if not _killed(outcome):
            break
        lost += 1
        if lost >= settings.max_attempts:
            _give_up(store, job_id, files, lost,
                     outcome.lost_why or f"its solver was killed by signal {-outcome.returncode}")
            return
        log.warning("%s: resuming from its checkpoint",
                    outcome.lost_why or f"solver killed by signal {-outcome.returncode}",
                    extra={"job_id": job_id, "lost": lost})
        _retry_redis(lambda: store.update_running(job_id, lost=lost))
    _finish(store, job_id, files, outcome, settings, quota)


def _clear_outputs(files: JobFiles) -> None:
    """A run again without a checkpoint starts from a clean folder."""
    for stale in (files.result, files.xdmf, files.log, files.dir / "preview.png"):
        stale.unlink(missing_ok=True)
    shutil.rmtree(files.previews, ignore_errors=True)


def _killed(outcome: Outcome) -> bool:
    """The solver process died by a signal we did not send (kill -9, out of memory)."""
    return outcome.stopped is None and outcome.returncode < 0


def _give_up(store: JobStore, job_id: str, files: JobFiles, lost: int, why: str) -> None:
    error = (f"the run was lost {lost} times (last: {why}); given up after MPM_MAX_ATTEMPTS = "
             f"{get_settings().max_attempts}")
    _retry_redis(lambda: store.transition(job_id, ACTIVE, "failed", error=error, lost=lost,
                                          eta_seconds=None, finished_at=now_iso()))
    checkpoint_path(files.dir).unlink(missing_ok=True)
    log.error("job failed: %s", error, extra={"job_id": job_id})


def _retry_redis(call, seconds: float = 300.0):
    """`call()`, tried again while Redis is away (restarting), up to `seconds`."""
    deadline = time.monotonic() + seconds
    while True:
        try:
            return call()
        except redis.RedisError as exc:
            if time.monotonic() > deadline:
                raise
            log.warning("redis unavailable, retrying: %s", exc)
            time.sleep(1.0)



def job_environment(settings: Settings) -> dict[str, str]:
    """The solver's environment: each of the jobs this worker runs at once gets its share
    of the cores for its threads (MPM_CORES, solver/threads.py), unless the operator set
    it (several workers on one machine)."""
    env = dict(os.environ)
    if "MPM_CORES" not in env:
        cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
        env["MPM_CORES"] = str(max(1, cores // settings.worker_concurrency))
    return env

def _finish(store: JobStore, job_id: str, files: JobFiles, outcome: Outcome, settings: Settings,
            quota: DiskQuota) -> None:
    done = outcome.done or {}
    extra = {"job_id": job_id, "returncode": outcome.returncode, "reason": done.get("reason")}
    if outcome.stopped == "shutdown":  # the solver left a checkpoint where it stopped
        _retry_redis(lambda: store.transition(job_id, ["running"], "queued", started_at=None))
        log.warning("job requeued: the worker is shutting down", extra=extra)
        raise Reject("worker shutting down", requeue=True)

    if outcome.stopped == "lease_lost":
        log.warning("job abandoned: its lease was lost to another worker", extra=extra)
        return

    final = {"finished_at": now_iso()}
    if outcome.stopped == "cancelled":
        status, error = "cancelled", None
    elif outcome.stopped == "timeout":
        status, error = "failed", (f"stopped after the time limit of {settings.max_job_seconds:g} s "
                                   "(MPM_MAX_JOB_SECONDS)")
    elif outcome.stopped == "disk_quota":
        status, error = "failed", f"stopped: {quota.reason}"
    elif outcome.returncode == 0 and done.get("status") == "complete":
        status, error = "succeeded", None
        final.update(progress=1.0)
    else:
        status = "failed"
        early = f"the run ended early ({done['reason']})" if done.get("reason") else None
        error = files.redact(done.get("message") or early or outcome.log_tail
                             or f"the solver exited with code {outcome.returncode}")
    if "steps" in done:
        final.update(step=done["steps"], sim_time=done.get("time"))
    _retry_redis(lambda: store.transition(job_id, ["running"], status, error=error, eta_seconds=None, **final))
    checkpoint_path(files.dir).unlink(missing_ok=True)  # over for good: nothing to resume
    log.info("job %s", status, extra={**extra, "error": error})
