"""The sweep routes: submit one job per combination of parameter values, follow the
sweep, list, cancel and delete it. A sweep is all or nothing: every combination is
validated and the quotas count every job before any is stored or queued."""
from __future__ import annotations

import logging
import uuid
from typing import Any

from fastapi import APIRouter, Query, Response
from pydantic import ConfigDict, Field

from core import sweeps
from core.models import ACTIVE, FINISHED, SweepMode, SweepRecord, now_iso
from service import quotas
from service.deps import CallerDep, OwnedSweep, ServicesDep
from service.errors import ApiError, documented, owned_resource, validation_error
from service.jobs import NewJob, checked_callback, new_job_from, remove_files, store_and_enqueue
from service.scenes import WrapsScene
from service.state import Services

log = logging.getLogger("mpm.api")
router = APIRouter(prefix="/v1/sweeps", tags=["sweeps"],
                   responses=owned_resource("sweep"))


class SweepRequest(WrapsScene):
    model_config = ConfigDict(extra="forbid")
    scene: dict[str, Any] = Field(description="the base scene")
    parameters: dict[str, list[Any]] = Field(
        min_length=1, description="JSON pointer into the scene -> its values, e.g. "
                                  '{"/materials/m/youngs_modulus": [1e6, 2e6]}')
    mode: SweepMode = Field("grid", description='"grid": every combination; "zip": the lists side by side')
    processes: int | None = Field(None, ge=1, description="processes for each job; capped by the service")
    callback_url: str | None = Field(None, max_length=2000,
                                     description="the sweep is POSTed there when its last job has ended")
    name: str | None = Field(None, max_length=200, description="default: the scene's name")


def _checked_parameters(body: SweepRequest, max_jobs: int) -> list[dict[str, Any]]:
    """The combinations, after the checks that need no scene: 422 naming the pointer."""
    problems = [{"path": f"parameters.{pointer}", "message": "has no values"}
                for pointer, values in body.parameters.items() if not values]
    lengths = {len(values) for values in body.parameters.values()}
    if body.mode == "zip" and len(lengths) > 1:
        problems.append({"path": "parameters", "message": "zip needs lists of one length, not "
                         + ", ".join(f"{p}: {len(v)}" for p, v in body.parameters.items())})
    if problems:
        raise validation_error(problems, "the sweep is not valid")
    count = sweeps.combination_count(body.parameters, body.mode)
    if count > max_jobs:
        raise validation_error([{"path": "parameters", "limit": "MPM_MAX_SWEEP_JOBS",
                                 "message": f"{count} combinations, over the limit of {max_jobs} jobs a sweep "
                                            "(MPM_MAX_SWEEP_JOBS)"}], "the sweep is over the service's limits")
    return sweeps.combinations(body.parameters, body.mode)


def _jobs_of(body: SweepRequest, combos: list[dict[str, Any]], sweep_id: str, owner: str | None,
             svc: Services) -> list[NewJob]:
    """A validated job per combination; the first combination that fails is a 422 naming
    its pointer(s), its index and its values, with the scene's errors."""
    jobs = []
    for index, combo in enumerate(combos):
        try:
            scene = sweeps.scene_of(body.scene, combo)
            jobs.append(new_job_from(scene, body.processes, owner, svc.settings, sweep=sweep_id,
                                     parameters=combo))
        except sweeps.PointerError as exc:
            pointer = next(p for p in combo if _fails(body.scene, p, combo[p]))
            raise validation_error([{"path": f"parameters.{pointer}", "combination": index, "values": combo,
                                     "message": str(exc)}], "the sweep is not valid") from None
        except ApiError as exc:
            details = [{**detail, "path": f"parameters.{_blamed(detail.get('path', ''), combo)}",
                        "scene_path": detail.get("path"), "combination": index, "values": combo}
                       for detail in exc.details or []]
            raise ApiError(exc.status, exc.code, f"combination {index} ({_show(combo)}): {exc.message}",
                           details, exc.headers) from None
    return jobs


def _fails(scene: dict[str, Any], pointer: str, value: Any) -> bool:
    try:
        sweeps.scene_of(scene, {pointer: value})
        return False
    except sweeps.PointerError:
        return True


def _blamed(scene_path: str, combo: dict[str, Any]) -> str:
    """The pointer whose place the scene's error is at (or under), else all of them."""
    for pointer in combo:
        dotted = ".".join(pointer.strip("/").split("/"))
        if scene_path == dotted or scene_path.startswith(dotted + ".") or scene_path.startswith(dotted + "["):
            return pointer
    return ",".join(combo)


def _show(combo: dict[str, Any]) -> str:
    return ", ".join(f"{pointer} = {value!r}" for pointer, value in combo.items())


@router.post("", status_code=202,
             responses=documented({429: "the sweep's jobs would go over a limit or a quota (none is queued)",
                                   507: "the disk budget is spent"}))
def submit_sweep(body: SweepRequest, svc: ServicesDep, owner: CallerDep) -> dict[str, Any]:
    """One job per combination; all are validated and admitted together, or none."""
    callback_url = checked_callback(body.callback_url, svc.settings)
    combos = _checked_parameters(body, svc.settings.max_sweep_jobs)
    quotas.check_count(len(combos), svc.settings)   # before validating a scene per combination
    sweep_id = str(uuid.uuid4())
    jobs = _jobs_of(body, combos, sweep_id, owner, svc)
    record = SweepRecord(id=sweep_id, name=body.name or body.scene.get("name"), owner=owner,
                         created_at=now_iso(), mode=body.mode, parameters=body.parameters,
                         jobs=[{"id": job.id, "parameters": job.record["parameters"]} for job in jobs],
                         callback_url=callback_url).model_dump(exclude_none=True)
    store_and_enqueue(svc, owner, jobs, sweep=record)
    log.info("sweep submitted", extra={"sweep_id": sweep_id, "jobs": len(jobs)})
    return sweeps.view(svc.store, record)


@router.get("")
def list_sweeps(svc: ServicesDep, owner: CallerDep, limit: int = Query(50, ge=1, le=500)) -> dict[str, Any]:
    """The caller's sweeps, newest first, each with its counts and progress."""
    found = [svc.store.get_sweep(sweep_id) for sweep_id in svc.store.sweep_ids(owner, limit)]
    return {"sweeps": [sweeps.view(svc.store, sweep) for sweep in found if sweep]}


@router.get("/{sweep_id}")
def get_sweep(sweep: OwnedSweep, svc: ServicesDep) -> dict[str, Any]:
    """The sweep: status counts, progress, each job's parameters and status."""
    return sweeps.view(svc.store, sweep)


@router.post("/{sweep_id}/cancel", status_code=202)
def cancel_sweep(record: OwnedSweep, svc: ServicesDep) -> dict[str, Any]:
    """Cancel every job of the sweep that has not finished."""
    for job in record["jobs"]:
        svc.store.request_cancel(job["id"])
    log.info("sweep cancel requested", extra={"sweep_id": record["id"]})
    return sweeps.view(svc.store, record)


@router.delete("/{sweep_id}", status_code=204, response_class=Response,
               responses=documented({409: "some of its jobs have not finished"}))
def delete_sweep(record: OwnedSweep, svc: ServicesDep, owner: CallerDep) -> Response:
    """Remove a finished sweep, its jobs and their files."""
    shown = sweeps.view(svc.store, record)
    active = sum(shown["counts"][s] for s in ACTIVE)
    if active:
        raise ApiError(409, "sweep_not_finished", f"{active} jobs of sweep {record['id']} have not finished; "
                       "cancel it first", {"counts": shown["counts"]})
    for job in record["jobs"]:
        if svc.store.delete(job["id"], allowed=FINISHED) in FINISHED:
            remove_files(svc, job["id"])
    svc.store.delete_sweep(record["id"], owner)
    log.info("sweep deleted", extra={"sweep_id": record["id"]})
    return Response(status_code=204)
