"""Refuse request bodies nested deeper than MPM_MAX_JSON_DEPTH with 422, before any
JSON parser sees them: Python's parser recurses, and a body of a million `[` would
exhaust its stack. A body that is not UTF-8 (as JSON must be) is a 422 too. (NaN and Infinity literals, which it accepts, are refused by the
scene's fields, each error naming its field.)

It runs inside the body-size limit, so the body it reads whole is bounded."""
from __future__ import annotations

import re

import numpy as np
from starlette.types import ASGIApp, Message, Receive, Scope, Send

from service.errors import error_response

_STRING = re.compile(rb'"(?:[^"\\]|\\.)*"', re.DOTALL)
_OPEN = np.zeros(256, dtype=np.int8)
_OPEN[[ord("["), ord("{")]] = 1
_OPEN[[ord("]"), ord("}")]] = -1


def nesting_depth(body: bytes) -> int:
    """The deepest nesting of arrays and objects (brackets inside strings do not count)."""
    outside = _STRING.sub(b'""', body)
    steps = _OPEN[np.frombuffer(outside, dtype=np.uint8)]
    return int(np.cumsum(steps, dtype=np.int64).max(initial=0))


class JsonDepthLimit:
    def __init__(self, app: ASGIApp, max_depth: int):
        self.app, self.max_depth = app, max_depth

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http" or scope["method"] not in ("POST", "PUT", "PATCH"):
            return await self.app(scope, receive, send)
        chunks, more = [], True
        while more:
            message = await receive()
            if message["type"] != "http.request":  # the client went away (or the size limit cut it)
                return await self.app(scope, _replay([message], receive), send)
            chunks.append(message.get("body", b""))
            more = message.get("more_body", False)
        body = b"".join(chunks)
        problem = self._problem(body)
        if problem:
            return await error_response(422, "validation_failed", "the request is not valid",
                                        [{"path": "", **problem}])(scope, receive, send)
        message = {"type": "http.request", "body": body, "more_body": False}
        await self.app(scope, _replay([message], receive), send)


    def _problem(self, body: bytes) -> dict[str, str] | None:
        try:
            body.decode("utf-8")
        except UnicodeDecodeError as exc:
            return {"message": f"not valid JSON: the body is not UTF-8 (byte {exc.start})"}
        if nesting_depth(body) > self.max_depth:
            return {"limit": "MPM_MAX_JSON_DEPTH",
                    "message": f"the JSON is nested more than {self.max_depth} levels deep (MPM_MAX_JSON_DEPTH)"}
        return None


def _replay(messages: list[Message], receive: Receive) -> Receive:
    """A receive() that hands out `messages`, then the server's (which waits for a disconnect)."""
    pending = list(messages)

    async def replay() -> Message:
        return pending.pop(0) if pending else await receive()
    return replay
