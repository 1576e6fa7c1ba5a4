"""A scripted fake of the HTTP API for the offline SDK tests, and job records to feed it."""
from __future__ import annotations

import json
from typing import Any, Callable

import httpx

BASE = "http://mpm.test"
JOB_ID = "0f5e6a4c-1d2b-4c3d-9e8f-a1b2c3d4e5f6"

Reply = httpx.Response | Exception | Callable[[httpx.Request], httpx.Response]


def job_record(status: str = "queued", **fields: Any) -> dict[str, Any]:
    """A job record as docs/internals.md describes it."""
    record = {
        "id": JOB_ID, "name": "two-disks", "status": status,
        "created_at": "2024-05-01T12:00:00Z", "started_at": None, "finished_at": None,
        "progress": 0.0, "step": 0, "sim_time": 0.0, "end_time": 3.5,
        "steps_per_second": None, "eta_seconds": None,
        "energies": {"kinetic": 0.0, "strain": 0.0, "total": 0.0},
        "error": None, "processes": 1,
        "summary": {"particles": 416, "grid_nodes": 441, "estimated_steps": 3500},
        "links": {"self": f"/v1/jobs/{JOB_ID}"},
    }
    record.update(fields)
    return record


def error(status: int, code: str, message: str, details: Any = None) -> httpx.Response:
    return httpx.Response(status, json={"error": {"code": code, "message": message, "details": details}})


class FakeService:
    """An ``httpx.MockTransport`` handler answering scripted replies per (method, path).

    ``on(method, path, *replies)`` serves the replies in turn and repeats the last;
    a reply is a response, an exception to raise (a connection error), or a
    function of the request. Every request is kept in ``requests``.
    """

    def __init__(self) -> None:
        self.requests: list[httpx.Request] = []
        self.routes: dict[tuple[str, str], list[Reply]] = {}

    def on(self, method: str, path: str, *replies: Reply) -> None:
        self.routes[(method, path)] = list(replies)

    def calls(self, method: str, path: str) -> list[httpx.Request]:
        return [r for r in self.requests if r.method == method and r.url.path == path]

    def __call__(self, request: httpx.Request) -> httpx.Response:
        self.requests.append(request)
        replies = self.routes.get((request.method, request.url.path))
        if not replies:
            return error(404, "not_found", f"no route {request.method} {request.url.path}")
        reply = replies.pop(0) if len(replies) > 1 else replies[0]
        if isinstance(reply, Exception):
            raise reply
        if callable(reply):
            return reply(request)
        return reply


def sent_json(request: httpx.Request) -> Any:
    return json.loads(request.content)
