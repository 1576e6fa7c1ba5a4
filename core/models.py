"""The job, defined once: its statuses and its record.

A record is stored as a Redis hash, one JSON-encoded value per field (core/store.py
writes and reads it; it refuses a field that is not one of `JobRecord`'s). The API
answers it with its links (service/jobs.py: `Job` is `JobFields` plus `links`), the
workers change it as they run the job (worker/tasks.py); docs/internals.md ("The job
record") shows one. The SDK (clients/python) and the dashboard (clients/web) have
their own copy of what they read of it: they are clients of the HTTP API only.
"""
from __future__ import annotations

from datetime import datetime, timezone
from typing import Any, Literal, get_args

from pydantic import BaseModel, ConfigDict

Status = Literal["queued", "running", "succeeded", "failed", "cancelled"]
STATUSES: tuple[Status, ...] = get_args(Status)
# A job goes queued -> running -> one of FINISHED, and never leaves a finished status.
ACTIVE: tuple[Status, ...] = ("queued", "running")
FINISHED: tuple[Status, ...] = ("succeeded", "failed", "cancelled")
assert sorted(ACTIVE + FINISHED) == sorted(STATUSES)


def now_iso() -> str:
    """The time as the records write it: ISO 8601, UTC, milliseconds, `Z`."""
    return datetime.now(timezone.utc).isoformat(timespec="milliseconds").replace("+00:00", "Z")


class JobFields(BaseModel):
    """A job record (docs/internals.md, "The job record")."""
    model_config = ConfigDict(extra="allow")
    id: str
    name: str | None
    status: Status
    created_at: str
    started_at: str | None
    finished_at: str | None
    progress: float
    step: int
    sim_time: float | None
    end_time: float | None
    steps_per_second: float | None
    eta_seconds: float | None
    # "queued" | "compiling" (a new variant's kernels) | "stepping" | "writing" (INTERFACES.md, third wave)
    stage: str | None = None
    energies: dict[str, float | None]
    error: str | None
    processes: int
    summary: dict[str, Any] | None


class JobRecord(JobFields):
    """What the store keeps of a job: the fields the API documents, and these (answered
    with the record too)."""
    owner: str | None              # whose token submitted it; None on a service without tokens
    cancel_requested: bool
    attempts: int                  # runs started
    # Written by the worker that runs the job (absent before).
    worker: str | None = None
    lost: int = 0                  # runs lost with their worker or solver process
    dt: float | None = None        # the latest time step
    # Given at submission (absent otherwise).
    callback_url: str | None = None  # the final record is POSTed there (worker/webhooks.py)
    sweep: str | None = None         # the sweep the job belongs to
    parameters: dict[str, Any] | None = None  # a sweep's job: its values, by JSON pointer
    nodes: int | None = None         # the nodes its processes spread over (MPM_LAUNCHER=slurm)


RECORD_FIELDS = frozenset(JobRecord.model_fields)


def new_job(job_id: str, owner: str | None, *, name: str | None, end_time: float | None,
            processes: int, summary: dict[str, Any], **given: Any) -> dict[str, Any]:
    """The record of a job as it is submitted: queued, nothing run yet; `given`: the
    submission's optional fields (callback_url, sweep, parameters) that are not None."""
    record = JobRecord(
        id=job_id, name=name, status="queued", created_at=now_iso(), started_at=None,
        finished_at=None, progress=0.0, step=0, sim_time=0.0, end_time=end_time,
        steps_per_second=None, eta_seconds=None, stage="queued", energies={"kinetic": 0.0, "strain": 0.0, "total": 0.0},
        error=None, processes=processes, summary=summary, owner=owner, cancel_requested=False, attempts=0,
        **{key: value for key, value in given.items() if value is not None})
    return record.model_dump(exclude_unset=True)  # not the worker's fields: they come when it runs


SweepMode = Literal["grid", "zip"]


class SweepJob(BaseModel):
    id: str
    parameters: dict[str, Any]   # JSON pointer -> the value this job has there


class SweepRecord(BaseModel):
    """A sweep: one job per combination of parameter values (service/sweeps.py). Its
    jobs are ordinary jobs (with `sweep` and `parameters` in their records); the sweep
    keeps which they are, in combination order. Stored as a Redis hash like a job."""
    id: str
    name: str | None
    owner: str | None
    created_at: str
    mode: SweepMode
    parameters: dict[str, list[Any]]   # JSON pointer -> its values, as submitted
    jobs: list[SweepJob]
    callback_url: str | None = None    # the sweep's record is POSTed there when its last job ends
    notified_at: str | None = None     # when that delivery was first queued (only one is)


SWEEP_FIELDS = frozenset(SweepRecord.model_fields)
