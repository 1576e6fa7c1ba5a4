"""The job routes: submit, list, show, cancel, delete, and the job's files."""
from __future__ import annotations

import json
import logging
import shutil
from dataclasses import dataclass
from typing import Any, Literal

from fastapi import APIRouter, Query, Response
from fastapi.responses import FileResponse, JSONResponse
from pydantic import BaseModel, ConfigDict, Field

from core import webhooks
from core.celery_app import enqueue
from core.models import FINISHED, STATUSES, JobFields, Status, new_job
from core.paths import JobFiles, new_job_id
from core.store import CursorError
from service import quotas, results
from service.deps import CallerDep, OwnedJob, ServicesDep, caller_job, job_not_found
from service.errors import ApiError, documented, owned_resource, validation_error
from service.scenes import WrapsScene, check_scene, granted_processes
from service.settings import ApiSettings
from service.state import Services

log = logging.getLogger("mpm.api")
FIELD_NAME = r"^[A-Za-z_][A-Za-z0-9_]{0,63}$"  # an output field's name (it becomes part of a cache file's name)
router = APIRouter(prefix="/v1/jobs", tags=["jobs"],
                   responses=owned_resource("job"))


class JobRequest(WrapsScene):
    model_config = ConfigDict(extra="forbid")
    scene: dict[str, Any] = Field(description="the scene document (see GET /v1/schema/scene)")
    processes: int | None = Field(None, ge=1, description="processes to run it on; capped by the service")
    nodes: int | None = Field(None, ge=1, le=4096, description="nodes the processes spread over on a Slurm "
                                                              "cluster (MPM_LAUNCHER=slurm); default 1")
    callback_url: str | None = Field(None, max_length=2000,
                                     description="the final job record is POSTed there, signed "
                                                 "(X-MPM-Signature); allowed hosts: MPM_WEBHOOK_ALLOW")


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
                    "series": f"{base}/series", "cancel": f"{base}/cancel", "scene": f"{base}/scene",
                    "frames": f"{base}/frames", "animation": f"{base}/animation.gif"}
    return job


@dataclass
class NewJob:
    """A validated job, not stored yet: its scene file's text and its record."""
    id: str
    scene_json: str
    record: dict[str, Any]


def new_job_from(scene_document: dict[str, Any], requested_processes: int | None, owner: str | None,
                 settings: ApiSettings, **given: Any) -> NewJob:
    """Validate the scene (422 with every error) and make the job's record; `given`: the
    record's optional fields (callback_url, sweep, parameters)."""
    scene_json, summary = check_scene(scene_document, settings)
    scene = json.loads(scene_json)
    job_id = new_job_id()
    record = new_job(job_id, owner, name=scene.get("name"), end_time=scene.get("time", {}).get("end"),
                     processes=granted_processes(requested_processes, scene, settings), summary=summary, **given)
    return NewJob(job_id, scene_json, record)


def store_and_enqueue(svc: Services, owner: str | None, jobs: list[NewJob],
                      sweep: dict[str, Any] | None = None) -> None:
    """Admit the jobs (disk, quotas: all or none), write their scene files and queue them.
    Anything refused or failing leaves no trace: no record, no folder, nothing queued."""
    quotas.check_disk(svc.disk, svc.settings)
    quota = quotas.owner_quota(owner, [job.record["summary"] for job in jobs], svc.settings)
    folders = [JobFiles(svc.settings.jobs_dir, job.id) for job in jobs]
    try:
        for job, files in zip(jobs, folders):
            files.dir.mkdir(parents=True)
            files.scene.write_text(job.scene_json, encoding="utf-8")
        quotas.admit(svc.store, {job.id: job.record for job in jobs}, quota, svc.settings, sweep)
        try:
            for job in jobs:
                enqueue(svc.celery, job.id)
        except Exception:
            for job in jobs:
                svc.store.delete(job.id, allowed=STATUSES)
            if sweep:
                svc.store.delete_sweep(sweep["id"], owner)
            raise
    except BaseException:
        for files in folders:
            shutil.rmtree(files.dir, ignore_errors=True)
        raise


def checked_callback(url: str | None, settings: ApiSettings, path: str = "callback_url") -> str | None:
    """The callback URL if the settings allow it; 422 naming the rule otherwise."""
    if url is None:
        return None
    try:
        return webhooks.check_url(url, settings)
    except webhooks.WebhookUrlError as exc:
        raise validation_error([{"path": path, "message": str(exc)}]) from None


@router.post("", status_code=202, response_model=Job,
             responses=documented({413: "request over MPM_MAX_BODY_BYTES",
                                   422: "every validation error, path and message",
                                   429: "over MPM_MAX_CONCURRENT_JOBS or one of the caller's quotas "
                                        "(details.limit names it; Retry-After)",
                                   507: "the disk budget is spent (MPM_MAX_TOTAL_BYTES, MPM_MIN_FREE_BYTES)"}))
def submit_job(body: JobRequest, svc: ServicesDep, owner: CallerDep) -> dict[str, Any]:
    """Validate the scene, store the job and put it on the queue. A rejected job leaves no trace."""
    callback_url = checked_callback(body.callback_url, svc.settings)
    job = new_job_from(body.scene, body.processes, owner, svc.settings, callback_url=callback_url,
                       nodes=body.nodes)
    store_and_enqueue(svc, owner, [job])
    log.info("job submitted", extra={"job_id": job.id, "job_name": job.record["name"],
                                     "particles": job.record["summary"].get("particles")})
    # The job as accepted; a worker may already have started it (GET shows that).
    return public(job.record)


@router.get("", response_model=JobList)
def list_jobs(status: Status | None = None, limit: int = Query(50, ge=1, le=500),
              cursor: str | None = None,
              id_prefix: str | None = Query(None, pattern=r"^[0-9a-f-]{1,36}$",
                                            description="only jobs whose id starts so (at most `limit`)"),
              *, svc: ServicesDep, owner: CallerDep) -> dict[str, Any]:
    """The caller's jobs, newest first; pass `next_cursor` back as `cursor` for the next page.
    With `id_prefix`: the jobs whose id starts with it (clients resolve a short id so)."""
    if id_prefix is not None:
        found = svc.store.jobs(svc.store.ids_with_prefix(id_prefix, owner, limit))
        return {"jobs": [public(job) for job in found if job and (status is None or job["status"] == status)],
                "next_cursor": None}
    try:
        page = svc.store.list(status, limit, cursor, owner=owner)
    except CursorError as exc:
        raise validation_error([{"path": "cursor", "message": exc.reason}]) from None
    return {"jobs": [public(job) for job in page.jobs], "next_cursor": page.next_cursor}


@router.get("/{job_id}", response_model=Job)
async def get_job(job: OwnedJob) -> JSONResponse:
    """One job; the route clients poll, so it is read without leaving the event loop."""
    return JSONResponse(public(job))  # the record is already the answer: no re-validation


@router.post("/{job_id}/cancel", status_code=202, response_model=Job,
             responses=documented({409: "the job has already finished"}))
def cancel_job(job: OwnedJob, svc: ServicesDep) -> dict[str, Any]:
    """A queued job is cancelled at once; a running one within a few seconds
    (its solver is stopped, the frames written so far stay readable)."""
    job_id = job["id"]
    before = svc.store.request_cancel(job_id)
    if before is None:
        raise job_not_found(job_id)
    if before in FINISHED:
        raise ApiError(409, "job_finished", f"job {job_id} has already {before}", {"status": before})
    log.info("job cancel requested", extra={"job_id": job_id, "status": before})
    after = svc.store.get(job_id)  # the record as the cancel left it
    if after is None:
        raise job_not_found(job_id)
    return public(after)


@router.delete("/{job_id}", status_code=204, response_class=Response,
               responses=documented({409: "the job has not finished"}))
def delete_job(job: OwnedJob, svc: ServicesDep) -> Response:
    """Remove a finished job and its files."""
    job_id = job["id"]
    status = svc.store.delete(job_id)
    if status is None:
        raise job_not_found(job_id)
    if status not in FINISHED:
        raise ApiError(409, "job_not_finished", f"job {job_id} is {status}; cancel it first",
                       {"status": status})
    remove_files(svc, job_id)
    log.info("job deleted", extra={"job_id": job_id})
    return Response(status_code=204)


def remove_files(svc: Services, job_id: str) -> None:
    shutil.rmtree(JobFiles(svc.settings.jobs_dir, job_id).dir, ignore_errors=True)


def _result_files(svc: Services, job: dict[str, Any], running_too: bool = False) -> tuple[JobFiles, bool]:
    """The files of a job that has a result file (a partial one counts), and whether
    the job has finished. A running job's file is offered only when `running_too`."""
    job_id, status = job["id"], job["status"]
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
def get_result(job: OwnedJob, svc: ServicesDep) -> FileResponse:
    """The HDF5 result (partial for a failed or cancelled job)."""
    files, _ = _result_files(svc, job)
    return FileResponse(files.result, media_type="application/x-hdf5",
                        filename=f"{files.dir.name}.h5")


@router.get("/{job_id}/preview.png", response_class=Response,
            responses={200: {"content": {"image/png": {}}}, **documented({409: "no result yet"})})
def get_preview(job_id: str, svc: ServicesDep, owner: CallerDep, frame: int = -1,
                field: str | None = Query(None, pattern=FIELD_NAME)) -> Response:
    """Frame `frame` (negative: from the end) coloured by `field` (default: the scene's
    preview field). Finished jobs' images are cached; a running job's are drawn each time."""
    files, finished = _result_files(svc, caller_job(svc, job_id, owner), running_too=True)
    png = results.preview(files, frame, field, cache=finished)
    if isinstance(png, bytes):
        return Response(png, media_type="image/png", headers={"Cache-Control": "no-store"})
    return FileResponse(png, media_type="image/png")


@router.get("/{job_id}/frames", responses=documented({409: "no result yet"}))
def get_frames(job: OwnedJob, svc: ServicesDep) -> dict[str, Any]:
    """The frames written so far (index, time, step, particles), the fields they can be
    coloured by, the axes (r and z for axisymmetric scenes) and the scene's units."""
    files, _ = _result_files(svc, job, running_too=True)
    return results.frames(files)


@router.get("/{job_id}/frames/{frame}/particles", response_class=Response,
            responses={200: {"content": {"application/octet-stream": {}},
                             "description": "uint32 header length, JSON header, float32 xyz, float32 values"},
                       **documented({409: "no result yet"})})
def get_particles(job_id: str, frame: int, svc: ServicesDep, owner: CallerDep,
                  field: str | None = Query(None, pattern=FIELD_NAME)) -> Response:
    """One frame's particle positions and one value each (`field`; default: the scene's
    preview field), packed for the dashboard's 3D viewer (docs/service.md)."""
    files, finished = _result_files(svc, caller_job(svc, job_id, owner), running_too=True)
    return Response(results.particles(files, frame, field), media_type="application/octet-stream",
                    headers={"Cache-Control": "private, max-age=3600" if finished else "no-store"})


@router.get("/{job_id}/animation.{kind}", response_class=FileResponse,
            responses={200: {"content": {"image/gif": {}, "video/mp4": {}}},
                       **documented({409: "no animation until the job has finished"})})
def get_animation(job_id: str, kind: Literal["gif", "mp4"], svc: ServicesDep, owner: CallerDep,
                  field: str | None = Query(None, pattern=FIELD_NAME)) -> FileResponse:
    """Every frame drawn like the previews, one colour scale for the run, as a GIF or an
    MP4 (H.264); rendered on the first request (seconds to a minute), then cached."""
    files, _ = _result_files(svc, caller_job(svc, job_id, owner))
    path = results.animation(files, field, f".{kind}")
    return FileResponse(path, media_type="image/gif" if kind == "gif" else "video/mp4")


@router.get("/{job_id}/series")
def get_series(job: OwnedJob, svc: ServicesDep) -> dict[str, list[float | None]]:
    """The time series written so far (time, dt, energies...), as lists."""
    files, _ = _result_files(svc, job, running_too=True)
    return results.series(files)


@router.get("/{job_id}/scene")
def get_scene(job: OwnedJob, svc: ServicesDep) -> dict[str, Any]:
    """The validated scene of the job."""
    job_id = job["id"]
    try:
        return json.loads(JobFiles(svc.settings.jobs_dir, job_id).scene.read_text(encoding="utf-8"))
    except FileNotFoundError:  # the folder was removed by hand
        raise ApiError(404, "not_found", f"job {job_id} has no scene file") from None


MAX_LOG_LINES = 5000


@router.get("/{job_id}/log", response_class=Response,
            responses={200: {"content": {"text/plain": {}},
                             "description": "the lines; X-MPM-Next-Line: the `since` of the next call"}})
def get_log(job_id: str, since: int = Query(0, ge=0, le=10**9), limit: int = Query(MAX_LOG_LINES, ge=1,
                                                                                         le=MAX_LOG_LINES),
            *, svc: ServicesDep, owner: CallerDep) -> Response:
    """The solver's log lines from line `since` (0: the first), at most `limit`; while
    the job runs, call again with X-MPM-Next-Line for the lines written since."""
    job = caller_job(svc, job_id, owner)
    job_id, status = job["id"], job["status"]
    lines: list[str] = []
    files = JobFiles(svc.settings.jobs_dir, job_id)
    try:
        with open(files.log, encoding="utf-8", errors="replace") as log_file:
            for number, line in enumerate(log_file):
                if number >= since + limit or not line.endswith("\n"):  # a line being written waits
                    break
                if number >= since:
                    lines.append(files.redact(line))   # the dashboard and `mpm log` show it: no server paths
    except FileNotFoundError:  # not started yet
        pass
    return Response("".join(lines), media_type="text/plain; charset=utf-8",
                    headers={"X-MPM-Next-Line": str(since + len(lines)), "X-MPM-Job-Status": status,
                             "Cache-Control": "no-store"})
