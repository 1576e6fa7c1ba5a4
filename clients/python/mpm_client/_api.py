"""What the sync and the async client share: the calls of the HTTP API and the retry policy.

Nothing here does I/O, so :class:`~mpm_client.Client` and
:class:`~mpm_client.AsyncClient` differ only in how they send and sleep.
"""
from __future__ import annotations

import os
import random
import re
import tempfile
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator
from urllib.parse import quote

import httpx

from .errors import JobCancelled, JobFailed, NotFound, ServiceUnavailable, error_from_response
from .scenes import SceneLike, scene_document

DEFAULT_SERVER = "http://127.0.0.1:8000"
RETRY_STATUSES = frozenset({502, 503, 504})
# Errors raised before a request reached the server: safe to retry for any method.
# Other transport errors (a read that broke off) are retried only for idempotent methods,
# so that a POST /v1/jobs is never submitted twice.
_NOT_SENT = (httpx.ConnectError, httpx.ConnectTimeout, httpx.PoolTimeout)
_IDEMPOTENT = frozenset({"GET", "HEAD", "PUT", "DELETE", "OPTIONS"})


@dataclass(frozen=True)
class Call:
    """One HTTP request of the API, described (not sent)."""

    method: str
    path: str
    params: dict[str, Any] | None = None
    json: Any = None
    # seconds to wait for the answer, when the client's own timeout is too short for it
    timeout: float | None = None

    @property
    def timeout_option(self) -> Any:
        return httpx.USE_CLIENT_DEFAULT if self.timeout is None else self.timeout


# An animation is rendered on its first request: up to a minute, more on a busy server.
ANIMATION_SECONDS = 600.0


def job_path(job_id: str, tail: str = "") -> str:
    return f"/v1/jobs/{quote(str(job_id), safe='')}{tail}"


def submit(scene: SceneLike, processes: int | None, callback_url: str | None = None,
           nodes: int | None = None) -> Call:
    body: dict[str, Any] = {"scene": scene_document(scene)}
    body.update({key: value for key, value in (("processes", processes), ("nodes", nodes),
                                               ("callback_url", callback_url))
                 if value is not None})
    return Call("POST", "/v1/jobs", json=body)


def validate(scene: SceneLike) -> Call:
    return Call("POST", "/v1/scenes/validate", json=scene_document(scene))


def list_jobs(status: str | None, limit: int | None, cursor: str | None) -> Call:
    params = {key: value for key, value in (("status", status), ("limit", limit), ("cursor", cursor))
              if value is not None}
    return Call("GET", "/v1/jobs", params=params)


FULL_ID = re.compile(r"^[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}$")
PREFIX = re.compile(r"^[0-9a-f-]{1,36}$")


def find_prefix(prefix: str) -> Call:
    """The jobs whose id starts with ``prefix`` (two at most: one means it is unique)."""
    if not PREFIX.match(prefix.lower()):  # no job id looks so
        raise NotFound(f"no job {prefix!r} (a job id, or its start, is hex digits and dashes)",
                       status_code=404, code="not_found")
    return Call("GET", "/v1/jobs", params={"id_prefix": prefix.lower(), "limit": 2})


def unique(prefix: str, found: list[dict[str, Any]]) -> str:
    """The id of the one job found for ``prefix``, or the error saying why not."""
    if not found:
        raise NotFound(f"no job {prefix!r}", status_code=404, code="not_found")
    if len(found) > 1:
        raise ValueError(f"{prefix!r} is the start of several jobs' ids ({found[0]['id'][:12]}..., "
                         f"{found[1]['id'][:12]}...): give more of it")
    return found[0]["id"]


def sweep(scene: SceneLike, parameters: dict[str, list[Any]], mode: str, processes: int | None,
          callback_url: str | None) -> Call:
    body: dict[str, Any] = {"scene": scene_document(scene), "parameters": parameters, "mode": mode}
    body.update({key: value for key, value in (("processes", processes), ("callback_url", callback_url))
                 if value is not None})
    return Call("POST", "/v1/sweeps", json=body)


def sweep_path(sweep_id: str, tail: str = "") -> str:
    return f"/v1/sweeps/{quote(str(sweep_id), safe='')}{tail}"


def preview(job_id: str, frame: int, field_name: str | None) -> Call:
    params: dict[str, Any] = {"frame": frame}
    if field_name:
        params["field"] = field_name
    return Call("GET", job_path(job_id, "/preview.png"), params=params)


def animation(job_id: str, path: str | os.PathLike[str], field_name: str | None) -> Call:
    """The job's animation in the format of ``path``'s suffix (.gif or .mp4)."""
    kind = Path(path).suffix.lower().lstrip(".")
    if kind not in ("gif", "mp4"):
        raise ValueError(f"cannot write {Path(path).name!r}: an animation is a .gif or an .mp4 file")
    return Call("GET", job_path(job_id, f"/animation.{kind}"), params={"field": field_name} if field_name else None,
                timeout=ANIMATION_SECONDS)


def example(name: str) -> Call:
    return Call("GET", f"/v1/examples/{quote(name, safe='')}")


@dataclass
class Retrier:
    """Decides, attempt by attempt, whether a call is tried again and after how long.

    Retries happen only on connection errors and 502/503/504 (never on 4xx), with
    exponential backoff and jitter; a ``Retry-After`` header is honoured up to
    ``max_backoff``. When the attempts run out the typed error is raised.
    """

    method: str
    retries: int = 3
    backoff: float = 0.25
    max_backoff: float = 8.0
    url: str = ""   # the service, named in the error when it cannot be reached
    attempt: int = field(default=0, init=False)

    def after(self, outcome: httpx.Response | httpx.TransportError) -> float | None:
        """:meth:`after_response` or :meth:`after_error`, whichever ``outcome`` of an attempt calls for."""
        if isinstance(outcome, httpx.TransportError):
            return self.after_error(outcome)
        return self.after_response(outcome)

    def after_error(self, exc: httpx.TransportError) -> float:
        """The delay before the next attempt, or raises :class:`ServiceUnavailable`."""
        retryable = isinstance(exc, _NOT_SENT) or self.method.upper() in _IDEMPOTENT
        if not retryable or self.attempt >= self.retries:
            where = f" at {self.url}" if self.url else ""
            raise ServiceUnavailable(f"cannot reach the service{where}: {exc}", status_code=None) from exc
        return self._next_delay(None)

    def after_response(self, response: httpx.Response) -> float | None:
        """None to accept the response, a delay to retry, or raises the typed error.

        The body of an error response must have been read (for streamed responses).
        """
        if response.status_code in RETRY_STATUSES and self.attempt < self.retries:
            return self._next_delay(response)
        if response.is_error:
            raise error_from_response(response)
        return None

    def _next_delay(self, response: httpx.Response | None) -> float:
        delay = min(self.max_backoff, self.backoff * 2 ** self.attempt) * random.uniform(0.5, 1.0)
        self.attempt += 1
        retry_after = response.headers.get("retry-after") if response is not None else None
        if retry_after and retry_after.replace(".", "", 1).isdigit():
            delay = min(self.max_backoff, float(retry_after))
        return delay


@contextmanager
def atomic_file(path: str | os.PathLike[str]) -> Iterator[Any]:
    """A binary file that appears at ``path`` only when the block completes.

    It is written beside the target and renamed over it, so a failed or
    interrupted download never leaves a half-written file behind.
    """
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    handle, temp_name = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".part", dir=target.parent)
    try:
        with os.fdopen(handle, "wb") as stream:
            yield stream
            stream.flush()
            os.fsync(stream.fileno())
        os.replace(temp_name, target)
    except BaseException:
        Path(temp_name).unlink(missing_ok=True)
        raise


def resolve_server(base_url: str | None) -> str:
    return (base_url or os.environ.get("MPM_SERVER") or DEFAULT_SERVER).rstrip("/")


def resolve_token(token: str | None) -> str | None:
    return token if token is not None else (os.environ.get("MPM_TOKEN") or None)


def headers(token: str | None) -> dict[str, str]:
    result = {"Accept": "application/json", "User-Agent": "mpm-client"}
    if token:
        result["Authorization"] = f"Bearer {token}"
    return result


def to_arrays(series: dict[str, Any]) -> dict[str, Any]:
    """The JSON time series as numpy arrays (numpy is imported only here)."""
    try:
        import numpy as np
    except ImportError:
        raise ImportError("Job.series() returns numpy arrays: pip install numpy") from None
    return {name: np.asarray(values, dtype=float) for name, values in series.items() if isinstance(values, list)}


def open_h5(path: Path) -> Any:
    try:
        import h5py
    except ImportError:
        raise ImportError("Job.open() returns an h5py.File: pip install h5py") from None
    return h5py.File(path, "r")


def finished(job: Any) -> Any:
    """Return a succeeded job (sync or async) or raise the error its status calls for."""
    record = job.record
    if record.status == "succeeded":
        return job
    if record.status == "cancelled":
        raise JobCancelled(job.id, record.status, record.error)
    raise JobFailed(job.id, record.status, record.error)


def result_path(job_id: str, path: str | os.PathLike[str] | None) -> Path:
    return Path(path) if path is not None else Path(tempfile.gettempdir()) / f"mpm-{job_id}.h5"


def sweep_line(record: dict[str, Any]) -> str:
    """``sweep 1a2b3c4d: 3/10 finished (2 running), 47 %``: a sweep's progress on one line."""
    counts = record["counts"]
    done = sum(counts.get(status, 0) for status in ("succeeded", "failed", "cancelled"))
    return (f"sweep {record['id'][:8]}: {done}/{len(record['jobs'])} finished "
            f"({counts.get('running', 0)} running), {100 * record['progress']:.0f} %")


def sweep_table(record: dict[str, Any]) -> str:
    pointers = list(record["parameters"])
    header = ["ID", *pointers, "STATUS", "KINETIC", "STRAIN", "TOTAL"]
    rows = [header]
    for job in record["jobs"]:
        energies = job.get("energies") or {}
        rows.append([job["id"][:8], *(str(job["parameters"].get(p)) for p in pointers), job["status"],
                     *(_number(energies.get(k)) for k in ("kinetic", "strain", "total"))])
    widths = [max(len(row[i]) for row in rows) for i in range(len(header))]
    return "\n".join("  ".join(cell.ljust(w) for cell, w in zip(row, widths)).rstrip() for row in rows)


def _number(value: Any) -> str:
    return "" if value is None else f"{value:.6g}"
