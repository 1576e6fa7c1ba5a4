"""Admission of jobs: the disk budget, the service's limit on queued + running jobs, and
each owner's quotas (active jobs, queued jobs, particle-steps a UTC day); on a service
without tokens the anonymous caller has the same quotas.

A job is charged particles x estimated steps (from the scene's summary) when it is
accepted; the charge is not refunded when it is cancelled or fails. The check and the
job's creation are one step in Redis (core/store.py), so concurrent submissions
cannot overrun a quota."""
from __future__ import annotations

from datetime import datetime, timedelta, timezone
from typing import Any

from core.disk import DiskUsage, human
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


def owner_quota(owner: str | None, summaries: list[dict[str, Any]], settings: ApiSettings) -> OwnerQuota:
    """The quota jobs are admitted under: the owner's, or on a service without tokens the
    anonymous caller's (the same MPM_QUOTA_* settings). Jobs bigger than a whole day's
    allowance can never fit: 422, not 429."""
    charge = sum(cost(summary) for summary in summaries)
    if charge > settings.quota_particle_steps_per_day:
        what = "this job" if len(summaries) == 1 else f"these {len(summaries)} jobs"
        raise validation_error([{
            "path": "scene", "limit": "MPM_QUOTA_PARTICLE_STEPS_PER_DAY",
            "message": f"{charge:.3g} particle-steps (particles x estimated steps) for {what} is more than a "
                       f"whole day's quota of {settings.quota_particle_steps_per_day:.3g} "
                       "(MPM_QUOTA_PARTICLE_STEPS_PER_DAY)"}], "the scene is over the service's limits")
    return OwnerQuota(owner, settings.quota_active_jobs, settings.quota_queued_jobs, charge,
                      settings.quota_particle_steps_per_day)


def check_disk(usage: DiskUsage, settings: ApiSettings) -> None:
    """507 with the figures when the jobs' folders are at MPM_MAX_TOTAL_BYTES or the file
    system has less than MPM_MIN_FREE_BYTES free: a job admitted then could not write."""
    used, free = usage.measure()
    if used >= settings.max_total_bytes:
        limit, message = "MPM_MAX_TOTAL_BYTES", (
            f"the results of all jobs take {human(used)}, at the limit of {human(settings.max_total_bytes)} "
            "(MPM_MAX_TOTAL_BYTES); delete finished jobs to make room")
    elif free < settings.min_free_bytes:
        limit, message = "MPM_MIN_FREE_BYTES", (
            f"the data folder's disk has {human(free)} free, less than the {human(settings.min_free_bytes)} "
            "a job needs (MPM_MIN_FREE_BYTES); delete finished jobs to make room")
    else:
        return
    raise ApiError(507, "insufficient_storage", message,
                   {"limit": limit, "used_bytes": used, "max_total_bytes": settings.max_total_bytes,
                    "free_bytes": free, "min_free_bytes": settings.min_free_bytes})


def admit(store: JobStore, jobs: dict[str, dict[str, Any]], quota: OwnerQuota, settings: ApiSettings,
          sweep: dict[str, Any] | None = None) -> None:
    """Create the jobs (and their sweep), all or none, or raise 429 naming the limit, with a Retry-After."""
    refused = store.admit_all(jobs, settings.max_concurrent_jobs, quota, sweep)
    if refused is None:
        return
    if refused == "owner_daily":
        count = "" if len(jobs) == 1 else f" ({len(jobs)} jobs asked for)"
        maximum = settings.quota_particle_steps_per_day
        used = store.usage_today(quota.owner or "")
        message = (f"{quota.cost:.3g} particle-steps{count} would take you over today's quota "
                   f"of {maximum:.3g} ({used:.3g} used); it resets at 00:00 UTC")
        raise _too_many("MPM_QUOTA_PARTICLE_STEPS_PER_DAY", maximum, _seconds_to_midnight(), message)
    raise _count_refusal(refused, len(jobs), settings)


def check_count(jobs: int, settings: ApiSettings) -> None:
    """429 at once when `jobs` together (a sweep's) are more than a limit on jobs at once
    allows even with none queued: decided from the count before any of them is validated
    (validating a thousand scenes to refuse them all takes seconds)."""
    for refused, maximum in (("max_active", settings.max_concurrent_jobs),
                             ("owner_active", settings.quota_active_jobs),
                             ("owner_queued", settings.quota_queued_jobs)):
        if jobs > maximum:
            raise _count_refusal(refused, jobs, settings)


def _count_refusal(refused: str, jobs: int, settings: ApiSettings) -> ApiError:
    count = "" if jobs == 1 else f" ({jobs} jobs asked for)"
    if refused == "max_active":
        limit, maximum, retry = "MPM_MAX_CONCURRENT_JOBS", settings.max_concurrent_jobs, 5
        message = f"the service takes {maximum} jobs queued or running at most{count}"
    elif refused == "owner_active":
        limit, maximum, retry = "MPM_QUOTA_ACTIVE_JOBS", settings.quota_active_jobs, RETRY_AFTER_JOBS
        message = f"you may have {maximum} jobs queued or running at most{count}"
    else:
        limit, maximum, retry = "MPM_QUOTA_QUEUED_JOBS", settings.quota_queued_jobs, RETRY_AFTER_JOBS
        message = f"you may have {maximum} jobs waiting in the queue at most{count}"
    return _too_many(limit, maximum, retry, message)


def _too_many(limit: str, maximum: float, retry: int, message: str) -> ApiError:
    return ApiError(429, "too_many_jobs", message, {"limit": limit, "max": maximum},
                    headers={"Retry-After": str(retry)})
