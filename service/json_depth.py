"""Refuse request bodies nested deeper than MPM_MAX_JSON_DEPTH with 422, before any
JSON parser sees them: Python's parser recurses, and a body of a million `[` would
exhaust its stack. A body that is not UTF-8 (as JSON must be) is a 422 too. (NaN and Infinity literals, which it accepts, are refused by the
scene's fields, each error naming its field.) A body that is not JSON by its Content-Type is a 415,
and an integer too long for Python's int conversion a 422 with its line and column.

It runs inside the body-size limit, so the body it reads whole is bounded."""
from __future__ import annotations

import re
import sys
from typing import Any

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
        if body and not _is_json(scope):
            return await error_response(415, "unsupported_media_type",
                                        "send application/json: the request bodies of this API are JSON "
                                        "documents (Content-Type: application/json)",
                                        {"content_type": _content_type(scope)[:100]})(scope, receive, send)
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
        return _long_integer(body)


def _content_type(scope: Scope) -> str:
    return dict(scope["headers"]).get(b"content-type", b"").decode("latin-1")


def _is_json(scope: Scope) -> bool:
    """application/json or a +json type (application/merge-patch+json), any parameters."""
    media = _content_type(scope).split(";")[0].strip().lower()
    return media == "application/json" or (media.startswith("application/") and media.endswith("+json"))


def _long_integer(body: bytes) -> dict[str, Any] | None:
    """An integer literal longer than Python's int conversion takes (sys.get_int_max_str_digits,
    4300 by default), with its line and column: the JSON parser would raise a ValueError
    without a position, which the framework answers 400."""
    limit = sys.get_int_max_str_digits()
    if not limit:
        return None
    outside = _STRING.sub(lambda m: b"_" * len(m.group()), body)   # same offsets, no digits of strings
    # an integer: not the digits of a fraction or an exponent (float() reads those at any length)
    found = re.search(rb"(?<![\d.eE+])(?<![eE]-)\d{%d,}(?![\d.eE])" % (limit + 1), outside)
    if found is None:
        return None
    line = body.count(b"\n", 0, found.start()) + 1
    column = found.start() - body.rfind(b"\n", 0, found.start())
    return {"line": line, "column": column,
            "message": f"not valid JSON: line {line}, column {column}: a number of {found.end() - found.start()} "
                       f"digits, more than the {limit} this service reads"}


def _replay(messages: list[Message], receive: Receive) -> Receive:
    """A receive() that hands out `messages`, then the server's (which waits for a disconnect)."""
    pending = list(messages)

    async def replay() -> Message:
        return pending.pop(0) if pending else await receive()
    return replay
