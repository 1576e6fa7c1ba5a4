"""Admission of a job: the service's limit on queued + running jobs, and, on a service
with tokens, each owner's quotas (active jobs, queued jobs, particle-steps a UTC day).

A job is charged particles x estimated steps (from the scene's summary) when it is
accepted; the charge is not refunded when it is cancelled or fails. The check and the
job's creation are one step in Redis (worker/store.py), so concurrent submissions
cannot overrun a quota."""
from __future__ import annotations

from datetime import datetime, timedelta, timezone
from typing import Any

from core.store import JobStore, OwnerQuota
from service.errors import ApiError, validation_error
from service.settings import ApiSettings

RETRY_AFTER_JOBS = 10  # seconds: a guess at when a job of the caller's will have finished


def cost(summary: dict[str, Any]) -> int:
    """Particle-steps of a job, estimated before it runs."""
    return int(summary.get("particles") or 0) * int(summary.get("estimated_steps") or 0)


def _seconds_to_midnight() -> int:
    now = datetime.now(timezone.utc)
    midnight = datetime.combine(now.date() + timedelta(days=1), datetime.min.time(), timezone.utc)
    return max(1, int((midnight - now).total_seconds()) + 1)


def owner_quota(owner: str | None, summary: dict[str, Any], settings: ApiSettings) -> OwnerQuota | None:
    """The quota the job is admitted under (None: a service without tokens has no owners).
    A job bigger than a whole day's allowance can never fit: 422, not 429."""
    if owner is None:
        return None
    charge = cost(summary)
    if charge > settings.quota_particle_steps_per_day:
        raise validation_error([{
            "path": "scene", "limit": "MPM_QUOTA_PARTICLE_STEPS_PER_DAY",
            "message": f"{charge:.3g} particle-steps (particles x estimated steps) is more than a whole "
                       f"day's quota of {settings.quota_particle_steps_per_day:.3g} "
                       "(MPM_QUOTA_PARTICLE_STEPS_PER_DAY)"}], "the scene is over the service's limits")
    return OwnerQuota(owner, settings.quota_active_jobs, settings.quota_queued_jobs, charge,
                      settings.quota_particle_steps_per_day)


def admit(store: JobStore, job_id: str, record: dict[str, Any], quota: OwnerQuota | None,
          settings: ApiSettings) -> None:
    """Create the job, or raise 429 naming the limit, with a Retry-After."""
    refused = store.admit(job_id, record, settings.max_concurrent_jobs, quota)
    if refused is None:
        return
    if refused == "max_active":
        limit, maximum, retry = "MPM_MAX_CONCURRENT_JOBS", settings.max_concurrent_jobs, 5
        message = f"{maximum} jobs are already queued or running"
    elif refused == "owner_active":
        limit, maximum, retry = "MPM_QUOTA_ACTIVE_JOBS", settings.quota_active_jobs, RETRY_AFTER_JOBS
        message = f"you already have {maximum} jobs queued or running"
    elif refused == "owner_queued":
        limit, maximum, retry = "MPM_QUOTA_QUEUED_JOBS", settings.quota_queued_jobs, RETRY_AFTER_JOBS
        message = f"you already have {maximum} jobs waiting in the queue"
    else:
        limit, maximum, retry = ("MPM_QUOTA_PARTICLE_STEPS_PER_DAY", settings.quota_particle_steps_per_day,
                                 _seconds_to_midnight())
        used = store.usage_today(quota.owner)
        message = (f"this job ({quota.cost:.3g} particle-steps) would take you over today's quota "
                   f"of {maximum:.3g} ({used:.3g} used); it resets at 00:00 UTC")
    raise ApiError(429, "too_many_jobs", message, {"limit": limit, "max": maximum},
                   headers={"Retry-After": str(retry)})
