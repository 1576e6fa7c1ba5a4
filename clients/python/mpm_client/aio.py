"""The asynchronous SDK: :class:`AsyncClient` and :class:`AsyncJob`, the same surface as the sync one.

Every method that talks to the service is a coroutine; ``jobs()`` is an async
iterator (``async for job in client.jobs(): ...``).
"""
from __future__ import annotations

import asyncio
import os
from pathlib import Path
from typing import Any, AsyncIterator

import httpx

from . import _api
from ._shared import ClientBase, JobHandle, JobWait
from .models import ExampleInfo, JobRecord, Summary
from .scenes import SceneLike


class AsyncClient(ClientBase):
    """The async twin of :class:`mpm_client.Client` (same arguments, same retries and errors)."""

    def __init__(self, base_url: str | None = None, token: str | None = None, *,
                 timeout: float = 30.0, retries: int = 3, backoff: float = 0.25,
                 transport: httpx.AsyncBaseTransport | None = None) -> None:
        super().__init__(base_url, token, timeout=timeout, retries=retries, backoff=backoff,
                         transport=transport, http_class=httpx.AsyncClient)

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

    async def _send(self, call: _api.Call) -> httpx.Response:
        retrier = self._retrier(call)
        while (delay := retrier.after(outcome := await self._attempt(call))) is not None:
            await asyncio.sleep(delay)
        return outcome

    async def _attempt(self, call: _api.Call) -> httpx.Response | httpx.TransportError:
        """One try of ``call``: the response, or the connection error that kept it from coming."""
        try:
            return await self._http.request(call.method, call.path, params=call.params, json=call.json)
        except httpx.TransportError as exc:
            return exc

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


class AsyncJob(JobHandle):
    """The async twin of :class:`mpm_client.Job`."""

    client: AsyncClient

    async def refresh(self) -> "AsyncJob":
        self.record = (await self.client.job(self.id)).record
        return self

    async def status(self) -> str:
        return (await self.refresh()).record.status

    async def wait(self, timeout: float | None = None, poll: float = 0.5, progress: bool = True) -> "AsyncJob":
        waiting = JobWait(self, timeout, poll, progress)
        try:
            while True:
                await self.refresh()
                pause = waiting.pause()
                if pause is None:
                    return self
                await asyncio.sleep(pause)
        finally:
            waiting.close()

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
        return _api.open_h5(self._result_on_disk(path) or await self.download(_api.result_path(self.id, path)))
