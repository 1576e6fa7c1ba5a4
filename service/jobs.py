"""The job routes: submit, list, show, cancel, delete, and the job's files."""
from __future__ import annotations

import json
import logging
import shutil
from typing import Any

from fastapi import APIRouter, Depends, Query, Response
from fastapi.responses import FileResponse, JSONResponse
from pydantic import BaseModel, ConfigDict, Field

from core.celery_app import enqueue
from core.models import FINISHED, STATUSES, JobFields, Status, new_job
from core.paths import InvalidJobId, JobFiles, new_job_id, parse_job_id
from core.store import CursorError, JobStore, job_key
from service import quotas, results
from service.auth import caller, owns
from service.errors import ApiError, documented, validation_error
from service.scenes import check_scene, granted_processes
from service.state import Services, services

log = logging.getLogger("mpm.api")
router = APIRouter(prefix="/v1/jobs", tags=["jobs"],
                   responses=documented({401: "no valid API token (when the service has tokens)",
                                         404: "no such job (or not the caller's)", 422: "invalid parameters"}))


class JobRequest(BaseModel):
    model_config = ConfigDict(extra="forbid")
    scene: dict[str, Any] = Field(description="the scene document (see GET /v1/schema/scene)")
    processes: int | None = Field(None, ge=1, description="processes to run it on; capped by the service")


class Job(JobFields):
    """A job record (docs/internals.md, "The job record")."""
    links: dict[str, str]


class JobList(BaseModel):
    jobs: list[Job]
    next_cursor: str | None


def public(record: dict[str, Any]) -> dict[str, Any]:
    job = dict(record)
    base = f"/v1/jobs/{record['id']}"
    job["links"] = {"self": base, "result": f"{base}/result.h5", "preview": f"{base}/preview.png",
                    "series": f"{base}/series", "cancel": f"{base}/cancel", "scene": f"{base}/scene"}
    return job


def _job_id(text: str) -> str:
    try:
        return parse_job_id(text)
    except InvalidJobId:
        raise _not_found(text) from None


def _not_found(job_id: str) -> ApiError:
    return ApiError(404, "not_found", f"no job {job_id}")


def _record(svc: Services, job_id: str, owner: str | None) -> dict[str, Any]:
    """The caller's job; another owner's is answered like a missing one, so ids do not leak."""
    record = svc.store.get(job_id)
    if record is None or not owns(record, owner):
        raise _not_found(job_id)
    return record


@router.post("", status_code=202, response_model=Job,
             responses=documented({413: "request over MPM_MAX_BODY_BYTES",
                                   422: "every validation error, path and message",
                                   429: "over MPM_MAX_CONCURRENT_JOBS or one of the caller's quotas "
                                        "(details.limit names it; Retry-After)"}))
def submit_job(body: JobRequest, svc: Services = Depends(services),
               owner: str | None = Depends(caller)) -> dict[str, Any]:
    """Validate the scene, store the job and put it on the queue. A rejected job leaves no trace."""
    scene_json, summary = check_scene(body.scene, svc.settings)
    scene = json.loads(scene_json)
    processes = granted_processes(body.processes, scene, svc.settings)
    quota = quotas.owner_quota(owner, summary, svc.settings)
    job_id = new_job_id()
    files = JobFiles(svc.settings.jobs_dir, job_id)
    files.dir.mkdir(parents=True)
    try:
        files.scene.write_text(scene_json, encoding="utf-8")
        record = new_job(job_id, owner, name=scene.get("name"), end_time=scene.get("time", {}).get("end"),
                         processes=processes, summary=summary)
        quotas.admit(svc.store, job_id, record, quota, svc.settings)
        try:
            enqueue(svc.celery, job_id)
        except Exception:
            svc.store.delete(job_id, allowed=STATUSES)
            raise
    except BaseException:
        shutil.rmtree(files.dir, ignore_errors=True)
        raise
    log.info("job submitted", extra={"job_id": job_id, "job_name": record["name"],
                                     "particles": summary.get("particles")})
    # The job as accepted; a worker may already have started it (GET shows that).
    return public(record)


@router.get("", response_model=JobList)
def list_jobs(status: Status | None = None, limit: int = Query(50, ge=1, le=500),
              cursor: str | None = None, svc: Services = Depends(services),
              owner: str | None = Depends(caller)) -> dict[str, Any]:
    """The caller's jobs, newest first; pass `next_cursor` back as `cursor` for the next page."""
    try:
        page = svc.store.list(status, limit, cursor, owner=owner)
    except CursorError as exc:
        raise validation_error([{"path": "cursor", "message": exc.reason}]) from None
    return {"jobs": [public(job) for job in page.jobs], "next_cursor": page.next_cursor}


@router.get("/{job_id}", response_model=Job)
async def get_job(job_id: str, svc: Services = Depends(services),
                  owner: str | None = Depends(caller)) -> JSONResponse:
    """One job; the route clients poll, so it reads Redis without leaving the event loop."""
    job_id = _job_id(job_id)
    record = JobStore.decode(await svc.async_redis.hgetall(job_key(job_id)))
    if record is None or not owns(record, owner):
        raise _not_found(job_id)
    return JSONResponse(public(record))  # the record is already the answer: no re-validation


@router.post("/{job_id}/cancel", status_code=202, response_model=Job,
             responses=documented({409: "the job has already finished"}))
def cancel_job(job_id: str, svc: Services = Depends(services),
               owner: str | None = Depends(caller)) -> dict[str, Any]:
    """A queued job is cancelled at once; a running one within a few seconds
    (its solver is stopped, the frames written so far stay readable)."""
    job_id = _job_id(job_id)
    _record(svc, job_id, owner)
    before = svc.store.request_cancel(job_id)
    if before is None:
        raise _not_found(job_id)
    if before in FINISHED:
        raise ApiError(409, "job_finished", f"job {job_id} has already {before}", {"status": before})
    log.info("job cancel requested", extra={"job_id": job_id, "status": before})
    return public(_record(svc, job_id, owner))


@router.delete("/{job_id}", status_code=204, response_class=Response,
               responses=documented({409: "the job has not finished"}))
def delete_job(job_id: str, svc: Services = Depends(services),
               owner: str | None = Depends(caller)) -> Response:
    """Remove a finished job and its files."""
    job_id = _job_id(job_id)
    _record(svc, job_id, owner)
    status = svc.store.delete(job_id)
    if status is None:
        raise _not_found(job_id)
    if status not in FINISHED:
        raise ApiError(409, "job_not_finished", f"job {job_id} is {status}; cancel it first",
                       {"status": status})
    shutil.rmtree(JobFiles(svc.settings.jobs_dir, job_id).dir, ignore_errors=True)
    log.info("job deleted", extra={"job_id": job_id})
    return Response(status_code=204)


def _result_files(svc: Services, job_id: str, owner: str | None,
                  running_too: bool = False) -> tuple[JobFiles, bool]:
    """The files of a job that has a result file (a partial one counts), and whether
    the job has finished. A running job's file is offered only when `running_too`."""
    job_id = _job_id(job_id)
    status = _record(svc, job_id, owner)["status"]
    files = JobFiles(svc.settings.jobs_dir, job_id)
    finished = status in FINISHED
    if not (finished or (running_too and status == "running")) or not files.result.is_file():
        raise ApiError(409, "result_not_ready",
                       f"job {job_id} is {status} and has no result file" + ("" if finished else " yet"),
                       {"status": status})
    return files, finished


@router.get("/{job_id}/result.h5", response_class=FileResponse,
            responses={200: {"content": {"application/x-hdf5": {}}},
                       **documented({409: "no result until the job has finished"})})
def get_result(job_id: str, svc: Services = Depends(services),
               owner: str | None = Depends(caller)) -> FileResponse:
    """The HDF5 result (partial for a failed or cancelled job)."""
    files, _ = _result_files(svc, job_id, owner)
    return FileResponse(files.result, media_type="application/x-hdf5",
                        filename=f"{files.dir.name}.h5")


@router.get("/{job_id}/preview.png", response_class=Response,
            responses={200: {"content": {"image/png": {}}}, **documented({409: "no result yet"})})
def get_preview(job_id: str, frame: int = -1,
                field: str | None = Query(None, pattern=r"^[A-Za-z_][A-Za-z0-9_]{0,63}$"),
                svc: Services = Depends(services), owner: str | None = Depends(caller)) -> Response:
    """Frame `frame` (negative: from the end) coloured by `field` (default: the scene's
    preview field). Finished jobs' images are cached; a running job's are drawn each time."""
    files, finished = _result_files(svc, job_id, owner, running_too=True)
    png = results.preview(files, frame, field, cache=finished)
    if isinstance(png, bytes):
        return Response(png, media_type="image/png", headers={"Cache-Control": "no-store"})
    return FileResponse(png, media_type="image/png")


@router.get("/{job_id}/series")
def get_series(job_id: str, svc: Services = Depends(services),
               owner: str | None = Depends(caller)) -> dict[str, list[float | None]]:
    """The time series written so far (time, dt, energies...), as lists."""
    files, _ = _result_files(svc, job_id, owner, running_too=True)
    return results.series(files)


@router.get("/{job_id}/scene")
def get_scene(job_id: str, svc: Services = Depends(services),
              owner: str | None = Depends(caller)) -> dict[str, Any]:
    """The validated scene of the job."""
    job_id = _job_id(job_id)
    _record(svc, job_id, owner)
    try:
        return json.loads(JobFiles(svc.settings.jobs_dir, job_id).scene.read_text(encoding="utf-8"))
    except FileNotFoundError:  # the folder was removed by hand
        raise ApiError(404, "not_found", f"job {job_id} has no scene file") from None
