"""What the routes take from FastAPI, as named types: the services, the caller, and the
caller's job or sweep named by the path. A job or sweep of another owner is answered
like a missing one (404), so ids do not leak.

FastAPI runs dependencies before it validates a route's own parameters, so a route that
declares other parameters (a frame, a field, a kind) looks its job up in its body with
`caller_job` instead of taking `OwnedJob`: a malformed parameter is a 422 whether or not
the job exists, as it is on every route."""
from __future__ import annotations

import uuid
from typing import Annotated, Any

from fastapi import Depends

from core.paths import InvalidJobId, parse_job_id
from service.auth import caller, owns
from service.errors import ApiError
from service.state import Services, services

ServicesDep = Annotated[Services, Depends(services)]
CallerDep = Annotated[str | None, Depends(caller)]


def job_not_found(job_id: str) -> ApiError:
    return ApiError(404, "not_found", f"no job {job_id}")


def canonical_job_id(job_id: str) -> str:
    try:
        return parse_job_id(job_id)
    except InvalidJobId:
        raise job_not_found(job_id) from None


def _the_callers(record: dict[str, Any] | None, job_id: str, owner: str | None) -> dict[str, Any]:
    if record is None or not owns(record, owner):
        raise job_not_found(job_id)
    return record


def caller_job(svc: Services, job_id: str, owner: str | None) -> dict[str, Any]:
    """The record of the caller's job `job_id` (its canonical id in record["id"])."""
    canonical = canonical_job_id(job_id)
    return _the_callers(svc.store.get(canonical), canonical, owner)


async def owned_job(job_id: str, svc: ServicesDep, owner: CallerDep) -> dict[str, Any]:
    """`caller_job` without leaving the event loop: a job's status is the route every client polls."""
    canonical = canonical_job_id(job_id)
    return _the_callers(await svc.store.get_async(canonical), canonical, owner)


def owned_sweep(sweep_id: str, svc: ServicesDep, owner: CallerDep) -> dict[str, Any]:
    """The record of the caller's sweep `sweep_id` (its canonical id in record["id"])."""
    try:
        canonical = str(uuid.UUID(sweep_id))
    except ValueError:
        raise ApiError(404, "not_found", f"no sweep {sweep_id}") from None
    record = svc.store.get_sweep(canonical)
    if record is None or not owns(record, owner):
        raise ApiError(404, "not_found", f"no sweep {canonical}")
    return record


OwnedJob = Annotated[dict[str, Any], Depends(owned_job)]
OwnedSweep = Annotated[dict[str, Any], Depends(owned_sweep)]
