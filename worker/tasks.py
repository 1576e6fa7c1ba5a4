"""The one Celery task: run one job from its record to a finished status.

The task is idempotent and safe to redeliver. A finished or deleted job is
skipped; a lease in Redis makes sure only one worker runs a job at a time (a
copy redelivered while the first run is alive finds the lease taken); a job
found `running` with a free lease was lost with its worker and is run again
from the start. When the worker shuts down the job goes back to the queue.
"""
from __future__ import annotations

import logging
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

from worker.celery_app import TASK_NAME
from worker.paths import JobFiles, parse_job_id
from worker.runner import Outcome, run_solver, solver_command
from worker.settings import get_settings
from worker.store import FINISHED, JobStore, now_iso

log = logging.getLogger("mpm.worker")

# Keys of the solver's progress line -> fields of the job record.
PROGRESS_FIELDS = {"fraction": "progress", "step": "step", "time": "sim_time",
                   "end_time": "end_time", "steps_per_second": "steps_per_second",
                   "eta_seconds": "eta_seconds", "energies": "energies", "dt": "dt"}

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
    job = store.get(job_id)
    if job is None or job["status"] in FINISHED:
        log.info("job skipped: finished or deleted", extra={"job_id": job_id})
        return
    token = f"{worker}:{uuid.uuid4()}"
    if not store.acquire_lease(job_id, token, get_settings().lease_seconds):
        log.warning("job skipped: another worker holds it", extra={"job_id": job_id})
        return
    try:
        _run_leased(store, job_id, job, worker, token)
    finally:
        store.release_lease(job_id, token)


def _run_leased(store: JobStore, job_id: str, job: dict[str, Any], worker: str, token: str) -> None:
    settings = get_settings()
    files = JobFiles(settings.jobs_dir, job_id)
    before = store.transition(
        job_id, ["queued", "running"], "running", started_at=now_iso(), worker=worker,
        attempts=job.get("attempts", 0) + 1, progress=0.0, step=0, sim_time=0.0,
        steps_per_second=None, eta_seconds=None, error=None)
    if before not in ("queued", "running"):
        log.info("job skipped: it is %s", before, extra={"job_id": job_id})
        return
    if before == "running":
        log.warning("job restarted: its worker was lost", extra={"job_id": job_id})
    # A rerun starts from a clean folder: only the scene is kept.
    for stale in (files.result, files.xdmf, files.log, files.dir / "preview.png"):
        stale.unlink(missing_ok=True)
    shutil.rmtree(files.previews, ignore_errors=True)
    if store.cancel_requested(job_id):
        store.transition(job_id, ["running"], "cancelled", finished_at=now_iso())
        return
    log.info("job started", extra={"job_id": job_id, "worker": worker})

    lease_renewed = time.monotonic()

    # A Redis hiccup must not end a long run: the checks and updates below skip a beat
    # instead. If Redis stays away longer than the lease, another worker takes the job
    # over, and this run stops when it finds its lease gone.
    def should_stop() -> str | None:
        nonlocal lease_renewed
        if _shutting_down.is_set():
            return "shutdown"
        try:
            if time.monotonic() - lease_renewed > settings.lease_seconds / 6:
                if not store.renew_lease(job_id, token, settings.lease_seconds):
                    return "lease_lost"
                lease_renewed = time.monotonic()
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

    outcome = run_solver(
        solver_command(files.scene, files.dir, job.get("processes", 1)), files.log,
        on_progress=on_progress, should_stop=should_stop,
        progress_interval=settings.progress_interval,
        grace_seconds=settings.cancel_grace_seconds,
        timeout_seconds=settings.max_job_seconds)
    _finish(store, job_id, outcome, settings.max_job_seconds)


def _finish(store: JobStore, job_id: str, outcome: Outcome, max_job_seconds: float) -> None:
    done = outcome.done or {}
    extra = {"job_id": job_id, "returncode": outcome.returncode, "reason": done.get("reason")}
    if outcome.stopped == "shutdown":
        store.transition(job_id, ["running"], "queued", started_at=None, progress=0.0, step=0)
        log.warning("job requeued: the worker is shutting down", extra=extra)
        raise Reject("worker shutting down", requeue=True)

    if outcome.stopped == "lease_lost":
        log.warning("job abandoned: its lease was lost to another worker", extra=extra)
        return

    final = {"finished_at": now_iso()}
    if outcome.stopped == "cancelled":
        status, error = "cancelled", None
    elif outcome.stopped == "timeout":
        status, error = "failed", f"stopped after the time limit of {max_job_seconds:g} s (MPM_MAX_JOB_SECONDS)"
    elif outcome.returncode == 0 and done.get("status") == "complete":
        status, error = "succeeded", None
        final.update(progress=1.0)
    else:
        status = "failed"
        early = f"the run ended early ({done['reason']})" if done.get("reason") else None
        error = (done.get("message") or early or outcome.log_tail
                 or f"the solver exited with code {outcome.returncode}")
    if "steps" in done:
        final.update(step=done["steps"], sim_time=done.get("time"))
    store.transition(job_id, ["running"], status, error=error, eta_seconds=None, **final)
    log.info("job %s", status, extra={**extra, "error": error})
