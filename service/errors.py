"""Every error answer is `{"error": {"code", "message", "details"}}`; no stack trace
ever reaches a client (it goes to the server log, with the request)."""
from __future__ import annotations

import logging
from typing import Any, Iterable, Sequence

import redis
from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from pydantic import BaseModel
from starlette.exceptions import HTTPException as StarletteHTTPException

log = logging.getLogger("mpm.api")

_CODES = {400: "bad_request", 401: "unauthorized", 403: "forbidden", 404: "not_found",
          405: "method_not_allowed", 409: "conflict", 413: "too_large", 422: "validation_failed",
          429: "too_many_jobs", 503: "unavailable", 507: "insufficient_storage"}


class ErrorDetail(BaseModel):
    code: str
    message: str
    details: Any = None


class ErrorBody(BaseModel):
    """Every error answer (for the OpenAPI document)."""
    error: ErrorDetail


def documented(descriptions: dict[int, str]) -> dict[int | str, dict[str, Any]]:
    """OpenAPI `responses` for error statuses ({status: description}), with the error body."""
    return {status: {"model": ErrorBody, "description": text} for status, text in descriptions.items()}


def owned_resource(noun: str) -> dict[int | str, dict[str, Any]]:
    """The error responses of a router of records that belong to their caller (jobs, sweeps)."""
    return documented({401: "no valid API token (when the service has tokens)",
                       404: f"no such {noun} (or not the caller's)", 422: "invalid parameters"})


class ApiError(Exception):
    def __init__(self, status: int, code: str, message: str, details: Any = None,
                 headers: dict[str, str] | None = None):
        super().__init__(message)
        self.status, self.code, self.message, self.details = status, code, message, details
        self.headers = headers


def error_response(status: int, code: str, message: str, details: Any = None,
                   headers: dict[str, str] | None = None) -> JSONResponse:
    return JSONResponse({"error": {"code": code, "message": message, "details": details}},
                        status_code=status, headers=headers)


def format_path(loc: Sequence[Any]) -> str:
    """("bodies", 1, "geometry", "radius") -> "bodies[1].geometry.radius"."""
    out = ""
    for part in loc:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            out += f".{part}" if out else str(part)
    return out


def validation_error(details: Iterable[dict[str, str]], message: str = "the request is not valid") -> ApiError:
    return ApiError(422, "validation_failed", message, list(details))


def _request_validation(request: Request, exc: RequestValidationError) -> JSONResponse:
    details = []
    for error in exc.errors():
        loc = list(error.get("loc", ()))
        if loc and loc[0] in ("body", "query", "path"):
            loc = loc[1:]
        if error.get("type") == "json_invalid":
            details.append(_json_syntax(error, loc, exc.body))
        else:
            details.append({"path": format_path(loc), "message": error["msg"]})
    return error_response(422, "validation_failed", "the request is not valid", details)


def _json_syntax(error: dict[str, Any], loc: list[Any], document: Any) -> dict[str, Any]:
    """A JSON syntax error, with its line and column (1-based, as json.JSONDecodeError counts
    them) when the parser gave the offset (FastAPI puts it in `loc`, the text in `body`)."""
    reason = error.get("ctx", {}).get("error", error["msg"])
    if not (loc and isinstance(loc[0], int) and isinstance(document, (str, bytes))):
        return {"path": "", "message": f"not valid JSON: {reason}"}
    text = document.decode("utf-8", "replace") if isinstance(document, bytes) else document
    offset = loc[0]
    line = text.count("\n", 0, offset) + 1
    column = offset - text.rfind("\n", 0, offset)
    return {"path": "", "line": line, "column": column,
            "message": f"not valid JSON: line {line}, column {column}: {reason}"}


def _api_error(request: Request, exc: ApiError) -> JSONResponse:
    return error_response(exc.status, exc.code, exc.message, exc.details, exc.headers)


def _http_error(request: Request, exc: StarletteHTTPException) -> JSONResponse:
    message = exc.detail if isinstance(exc.detail, str) else "error"
    return error_response(exc.status_code, _CODES.get(exc.status_code, "error"), message,
                          headers=getattr(exc, "headers", None))


def _store_unavailable(request: Request, exc: redis.RedisError) -> JSONResponse:
    """Redis is down or restarting: nothing is lost (docs/reliability.md), ask to retry."""
    log.warning("redis unavailable: %s", exc, extra={"method": request.method, "path": request.url.path})
    return error_response(503, "unavailable", "the job store (Redis) is not reachable; retry shortly",
                          headers={"Retry-After": "2"})


def _unexpected(request: Request, exc: Exception) -> JSONResponse:
    log.error("unhandled error", exc_info=exc,
              extra={"method": request.method, "path": request.url.path})
    return error_response(500, "internal_error", "internal error; the server log has the details")


def install(app: FastAPI) -> None:
    app.add_exception_handler(ApiError, _api_error)
    app.add_exception_handler(RequestValidationError, _request_validation)
    app.add_exception_handler(StarletteHTTPException, _http_error)
    app.add_exception_handler(redis.RedisError, _store_unavailable)
    app.add_exception_handler(Exception, _unexpected)
