"""The asynchronous SDK: :class:`AsyncClient` and :class:`AsyncJob`, the same surface as the sync one.

Every method that talks to the service is a coroutine; ``jobs()`` is an async
iterator (``async for job in client.jobs(): ...``).
"""
from __future__ import annotations

import asyncio
import os
import time
from pathlib import Path
from typing import Any, AsyncIterator

import httpx

from . import _api
from .errors import WaitTimeout
from .models import ExampleInfo, JobRecord, Summary
from .progress import ProgressBar
from .scenes import SceneLike


class AsyncClient:
    """The async twin of :class:`mpm_client.Client` (same arguments, same retries and errors)."""

    def __init__(self, base_url: str | None = None, token: str | None = None, *,
                 timeout: float = 30.0, retries: int = 3, backoff: float = 0.25,
                 transport: httpx.AsyncBaseTransport | None = None) -> None:
        self.base_url = _api.resolve_server(base_url)
        self.retries = retries
        self.backoff = backoff
        self._http = httpx.AsyncClient(base_url=self.base_url, headers=_api.headers(_api.resolve_token(token)),
                                       timeout=timeout, transport=transport)

    async def __aenter__(self) -> "AsyncClient":
        return self

    async def __aexit__(self, *exc_info: object) -> None:
        await self.aclose()

    async def aclose(self) -> None:
        await self._http.aclose()

    def __repr__(self) -> str:
        return f"AsyncClient({self.base_url!r})"

    async def submit(self, scene: SceneLike, processes: int | None = None,
                     nodes: int | None = None) -> "AsyncJob":
        return self._job((await self._send(_api.submit(scene, processes, nodes=nodes))).json())

    async def validate(self, scene: SceneLike) -> Summary:
        return Summary.model_validate((await self._send(_api.validate(scene))).json()["summary"])

    async def jobs(self, status: str | None = None, limit: int | None = None) -> AsyncIterator["AsyncJob"]:
        cursor = None
        while True:
            page = (await self._send(_api.list_jobs(status, limit, cursor))).json()
            for record in page["jobs"]:
                yield self._job(record)
            cursor = page.get("next_cursor")
            if not cursor:
                return

    async def job(self, job_id: str) -> "AsyncJob":
        return self._job((await self._send(_api.Call("GET", _api.job_path(job_id)))).json())

    async def examples(self) -> list[ExampleInfo]:
        answer = (await self._send(_api.Call("GET", "/v1/examples"))).json()
        return [ExampleInfo.model_validate(item) for item in answer["examples"]]

    async def example(self, name: str) -> dict[str, Any]:
        return (await self._send(_api.example(name))).json()

    def _job(self, record: dict[str, Any]) -> "AsyncJob":
        return AsyncJob(self, JobRecord.model_validate(record))

    def _retrier(self, call: _api.Call) -> _api.Retrier:
        return _api.Retrier(call.method, retries=self.retries, backoff=self.backoff, url=self.base_url)

    async def _send(self, call: _api.Call) -> httpx.Response:
        retrier = self._retrier(call)
        while True:
            try:
                response = await self._http.request(call.method, call.path, params=call.params, json=call.json)
            except httpx.TransportError as exc:
                delay = retrier.after_error(exc)
            else:
                delay = retrier.after_response(response)
                if delay is None:
                    return response
            await asyncio.sleep(delay)

    async def _download(self, call: _api.Call, path: str | os.PathLike[str]) -> Path:
        retrier = self._retrier(call)
        while True:
            try:
                async with self._http.stream(call.method, call.path, params=call.params,
                                             timeout=call.timeout_option) as response:
                    if response.is_error:
                        await response.aread()
                    delay = retrier.after_response(response)
                    if delay is None:
                        with _api.atomic_file(path) as out:
                            async for chunk in response.aiter_bytes():
                                out.write(chunk)
                        return Path(path)
            except httpx.TransportError as exc:
                delay = retrier.after_error(exc)
            await asyncio.sleep(delay)


class AsyncJob:
    """The async twin of :class:`mpm_client.Job`."""

    def __init__(self, client: AsyncClient, record: JobRecord) -> None:
        self.client = client
        self.record = record
        self._downloaded: Path | None = None

    @property
    def id(self) -> str:
        return self.record.id

    def __repr__(self) -> str:
        return f"AsyncJob({self.id!r}, status={self.record.status!r}, progress={self.record.progress:.2f})"

    async def refresh(self) -> "AsyncJob":
        self.record = (await self.client.job(self.id)).record
        return self

    async def status(self) -> str:
        return (await self.refresh()).record.status

    async def wait(self, timeout: float | None = None, poll: float = 0.5, progress: bool = True) -> "AsyncJob":
        bar = ProgressBar() if progress else None
        deadline = None if timeout is None else time.monotonic() + timeout
        try:
            while True:
                await self.refresh()
                if bar:
                    bar.update(self.record)
                if self.record.finished:
                    return _api.finished(self)
                if deadline is not None and time.monotonic() >= deadline:
                    raise WaitTimeout(f"job {self.id} still {self.record.status} after {timeout} s")
                await asyncio.sleep(poll if deadline is None else max(0.0, min(poll, deadline - time.monotonic())))
        finally:
            if bar:
                bar.close()

    async def cancel(self) -> "AsyncJob":
        await self.client._send(_api.Call("POST", _api.job_path(self.id, "/cancel")))
        return await self.refresh()

    async def delete(self) -> None:
        await self.client._send(_api.Call("DELETE", _api.job_path(self.id)))

    async def download(self, path: str | os.PathLike[str]) -> Path:
        self._downloaded = await self.client._download(_api.Call("GET", _api.job_path(self.id, "/result.h5")), path)
        return self._downloaded

    async def preview(self, frame: int = -1, field: str | None = None,
                      path: str | os.PathLike[str] | None = None) -> bytes:
        image = (await self.client._send(_api.preview(self.id, frame, field))).content
        if path is not None:
            with _api.atomic_file(path) as out:
                out.write(image)
        return image

    async def animate(self, path: str | os.PathLike[str], field: str | None = None) -> Path:
        return await self.client._download(_api.animation(self.id, path, field), path)

    async def series(self) -> dict[str, Any]:
        return _api.to_arrays((await self.client._send(_api.Call("GET", _api.job_path(self.id, "/series")))).json())

    async def scene(self) -> dict[str, Any]:
        return (await self.client._send(_api.Call("GET", _api.job_path(self.id, "/scene")))).json()

    async def open(self, path: str | os.PathLike[str] | None = None) -> Any:
        candidate = Path(path) if path is not None else self._downloaded
        if candidate is None or not candidate.is_file():
            candidate = await self.download(_api.result_path(self.id, path))
        return _api.open_h5(candidate)
