"""The synchronous SDK: :class:`Client` and :class:`Job`."""
from __future__ import annotations

import os
import sys
import time
from pathlib import Path
from typing import Any, Iterator

import httpx

from . import _api
from ._shared import ClientBase, JobHandle, JobWait
from .errors import WaitTimeout
from .models import ExampleInfo, JobRecord, Summary
from .scenes import SceneLike


class Client(ClientBase):
    """A connection to the MPM service.

    ``base_url`` defaults to ``$MPM_SERVER`` (else ``http://127.0.0.1:8000``) and
    ``token`` to ``$MPM_TOKEN``. Connection errors and 502/503/504 answers are
    retried ``retries`` times with exponential backoff; 4xx answers never are.
    ``transport`` is handed to httpx (tests pass an ``httpx.MockTransport``).
    """

    def __init__(self, base_url: str | None = None, token: str | None = None, *,
                 timeout: float = 30.0, retries: int = 3, backoff: float = 0.25,
                 transport: httpx.BaseTransport | None = None) -> None:
        super().__init__(base_url, token, timeout=timeout, retries=retries, backoff=backoff,
                         transport=transport, http_class=httpx.Client)

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc_info: object) -> None:
        self.close()

    def close(self) -> None:
        self._http.close()

    def __repr__(self) -> str:
        return f"Client({self.base_url!r})"

    # -- the API ---------------------------------------------------------------

    def submit(self, scene: SceneLike, processes: int | None = None, callback_url: str | None = None,
               nodes: int | None = None) -> "Job":
        """Validate, store and enqueue a scene (dict, file path, JSON text or solver ``Scene``);
        with ``callback_url`` the service POSTs the final job record there, signed; ``nodes``
        spreads the processes over that many nodes of a Slurm cluster (MPM_LAUNCHER=slurm)."""
        return self._job(self._send(_api.submit(scene, processes, callback_url, nodes)).json())

    def sweep(self, scene: SceneLike, parameters: dict[str, list[Any]], mode: str = "grid", *,
              processes: int | None = None, callback_url: str | None = None) -> "Sweep":
        """One job per combination of ``parameters`` ({JSON pointer into the scene: values});
        ``mode`` "grid": every combination, "zip": the lists side by side. All the
        combinations are validated before any job is queued (:class:`ValidationFailed`)."""
        return Sweep(self, self._send(_api.sweep(scene, parameters, mode, processes, callback_url)).json())

    def get_sweep(self, sweep_id: str) -> "Sweep":
        return Sweep(self, self._send(_api.Call("GET", _api.sweep_path(sweep_id))).json())

    def sweeps(self, limit: int = 50) -> list["Sweep"]:
        """This caller's sweeps, newest first."""
        answer = self._send(_api.Call("GET", "/v1/sweeps", params={"limit": limit})).json()
        return [Sweep(self, record) for record in answer["sweeps"]]

    def validate(self, scene: SceneLike) -> Summary:
        """The summary of a valid scene; raises :class:`ValidationFailed` with every error."""
        return Summary.model_validate(self._send(_api.validate(scene)).json()["summary"])

    def jobs(self, status: str | None = None, limit: int | None = None) -> Iterator["Job"]:
        """Every job of this caller, newest first, fetched page by page (``limit`` jobs a page)."""
        cursor = None
        while True:
            page = self._send(_api.list_jobs(status, limit, cursor)).json()
            for record in page["jobs"]:
                yield self._job(record)
            cursor = page.get("next_cursor")
            if not cursor:
                return

    def job(self, job_id: str) -> "Job":
        """A job by its id or a unique start of it (as `mpm jobs` and the dashboard show)."""
        return self._job(self._send(_api.Call("GET", _api.job_path(self.resolve(job_id)))).json())

    def resolve(self, job_id: str) -> str:
        """The full id of the job whose id is or starts with ``job_id``."""
        if _api.FULL_ID.match(job_id.lower()):
            return job_id.lower()
        return _api.unique(job_id, self._send(_api.find_prefix(job_id)).json()["jobs"])

    def examples(self) -> list[ExampleInfo]:
        answer = self._send(_api.Call("GET", "/v1/examples")).json()
        return [ExampleInfo.model_validate(item) for item in answer["examples"]]

    def example(self, name: str) -> dict[str, Any]:
        """The scene document of a built-in example."""
        return self._send(_api.example(name)).json()

    # -- plumbing ----------------------------------------------------------------

    def _job(self, record: dict[str, Any]) -> "Job":
        return Job(self, JobRecord.model_validate(record))

    def _send(self, call: _api.Call) -> httpx.Response:
        retrier = self._retrier(call)
        while (delay := retrier.after(outcome := self._attempt(call))) is not None:
            time.sleep(delay)
        return outcome

    def _attempt(self, call: _api.Call) -> httpx.Response | httpx.TransportError:
        """One try of ``call``: the response, or the connection error that kept it from coming."""
        try:
            return self._http.request(call.method, call.path, params=call.params, json=call.json)
        except httpx.TransportError as exc:
            return exc

    def _download(self, call: _api.Call, path: str | os.PathLike[str]) -> Path:
        """Stream the answer of ``call`` into ``path``; a broken transfer starts over, never half-writes."""
        retrier = self._retrier(call)
        while True:
            try:
                with self._http.stream(call.method, call.path, params=call.params,
                                       timeout=call.timeout_option) as response:
                    if response.is_error:
                        response.read()
                    delay = retrier.after_response(response)
                    if delay is None:
                        with _api.atomic_file(path) as out:
                            for chunk in response.iter_bytes():
                                out.write(chunk)
                        return Path(path)
            except httpx.TransportError as exc:
                delay = retrier.after_error(exc)
            time.sleep(delay)


class Job(JobHandle):
    """A submitted job. ``record`` is the last :class:`JobRecord` fetched (see :meth:`refresh`)."""

    client: Client

    def refresh(self) -> "Job":
        """Fetch the job record again."""
        self.record = self.client.job(self.id).record
        return self

    def status(self) -> str:
        """The current status (fetched): queued, running, succeeded, failed or cancelled."""
        return self.refresh().record.status

    def wait(self, timeout: float | None = None, poll: float = 0.5, progress: bool = True) -> "Job":
        """Block until the job finishes; returns it when it succeeded.

        Raises :class:`JobFailed` (with the solver's diagnostic) when it failed,
        :class:`JobCancelled` when it was cancelled, :class:`WaitTimeout` after
        ``timeout`` seconds (the job keeps running).
        """
        waiting = JobWait(self, timeout, poll, progress)
        try:
            while True:
                self.refresh()
                pause = waiting.pause()
                if pause is None:
                    return self
                time.sleep(pause)
        finally:
            waiting.close()

    def cancel(self) -> "Job":
        """Ask the service to stop the job; raises :class:`Conflict` if it already finished."""
        self.client._send(_api.Call("POST", _api.job_path(self.id, "/cancel")))
        return self.refresh()

    def delete(self) -> None:
        """Remove a finished job and its files from the service."""
        self.client._send(_api.Call("DELETE", _api.job_path(self.id)))

    def download(self, path: str | os.PathLike[str]) -> Path:
        """Stream ``result.h5`` to ``path`` (written atomically); raises :class:`Conflict` while there is none."""
        self._downloaded = self.client._download(_api.Call("GET", _api.job_path(self.id, "/result.h5")), path)
        return self._downloaded

    def preview(self, frame: int = -1, field: str | None = None,
                path: str | os.PathLike[str] | None = None) -> bytes:
        """The PNG of a frame (the last by default), also written to ``path`` when given."""
        image = self.client._send(_api.preview(self.id, frame, field)).content
        if path is not None:
            with _api.atomic_file(path) as out:
                out.write(image)
        return image

    def animate(self, path: str | os.PathLike[str], field: str | None = None) -> Path:
        """Every frame as an animation, written to ``path``: a ``.gif`` or an ``.mp4`` (H.264),
        coloured by ``field`` (default: the scene's preview field). The service renders it
        once the job has finished (seconds to a minute the first time) and keeps it."""
        return self.client._download(_api.animation(self.id, path, field), path)

    def series(self) -> dict[str, Any]:
        """The time series (time, dt, kinetic_energy, ...) as numpy arrays (needs numpy)."""
        return _api.to_arrays(self.client._send(_api.Call("GET", _api.job_path(self.id, "/series"))).json())

    def log(self, since: int = 0) -> tuple[str, int]:
        """The solver's log lines from line ``since`` on, and the ``since`` of the next call."""
        answer = self.client._send(_api.Call("GET", _api.job_path(self.id, "/log"), params={"since": since}))
        return answer.text, int(answer.headers.get("x-mpm-next-line", since))

    def scene(self) -> dict[str, Any]:
        """The validated scene the job runs."""
        return self.client._send(_api.Call("GET", _api.job_path(self.id, "/scene"))).json()

    def open(self, path: str | os.PathLike[str] | None = None) -> Any:
        """The result as an open ``h5py.File`` (needs h5py); close it when done.

        Uses ``path`` if that file exists, else downloads to it; without ``path``
        it reuses the last :meth:`download` or downloads into the temp directory.
        """
        return _api.open_h5(self._result_on_disk(path) or self.download(_api.result_path(self.id, path)))


class Sweep:
    """A submitted sweep. ``record`` is the last answer of ``GET /v1/sweeps/{id}`` (see
    :meth:`refresh`): ``status``, ``counts``, ``progress`` and ``jobs``."""

    def __init__(self, client: Client, record: dict[str, Any]) -> None:
        self.client = client
        self.record = record

    @property
    def id(self) -> str:
        return self.record["id"]

    @property
    def jobs(self) -> list[dict[str, Any]]:
        """Each job: ``id``, ``parameters`` ({pointer: value}), ``status``, ``progress``, ``energies``."""
        return self.record["jobs"]

    def __repr__(self) -> str:
        return f"Sweep({self.id!r}, status={self.record['status']!r}, jobs={len(self.jobs)})"

    def refresh(self) -> "Sweep":
        self.record = self.client._send(_api.Call("GET", _api.sweep_path(self.id))).json()
        return self

    def wait(self, timeout: float | None = None, poll: float = 1.0, progress: bool = True) -> "Sweep":
        """Block until every job has finished (whatever its end); :class:`WaitTimeout` after ``timeout``."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            self.refresh()
            if progress:
                print(_api.sweep_line(self.record), end="\r", file=sys.stderr, flush=True)
            if self.record["status"] == "finished":
                if progress:
                    print(file=sys.stderr)
                return self
            if deadline is not None and time.monotonic() >= deadline:
                raise WaitTimeout(f"sweep {self.id} still {self.record['status']} after {timeout} s")
            time.sleep(poll)

    def table(self) -> str:
        """The parameters beside each job's status and final energies, one row a job."""
        return _api.sweep_table(self.record)

    def cancel(self) -> "Sweep":
        self.record = self.client._send(_api.Call("POST", _api.sweep_path(self.id, "/cancel"))).json()
        return self

    def delete(self) -> None:
        """Remove the finished sweep, its jobs and their files."""
        self.client._send(_api.Call("DELETE", _api.sweep_path(self.id)))
