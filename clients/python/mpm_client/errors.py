"""Typed errors of the SDK, and the mapping from HTTP answers to them.

Every error the service answers has the body ``{"error": {"code", "message",
"details"}}``; :func:`error_from_response` turns it into one of the classes
below so callers can ``except NotFound`` instead of checking status codes.
"""
from __future__ import annotations

from typing import Any

import httpx


class MpmError(Exception):
    """Base of every error raised by the SDK."""


class ApiError(MpmError):
    """The service answered with an error status.

    ``status_code`` is the HTTP status (None when no answer came at all),
    ``code`` the machine-readable error code of the body (``"not_found"``, ...),
    ``details`` whatever the service added.
    """

    def __init__(self, message: str, *, status_code: int | None, code: str | None = None,
                 details: Any = None) -> None:
        super().__init__(message)
        self.message = message
        self.status_code = status_code
        self.code = code
        self.details = details


class ValidationFailed(ApiError):
    """The scene was rejected (422); ``errors`` lists every path and message."""

    def __init__(self, message: str, *, status_code: int = 422, code: str | None = None,
                 details: Any = None) -> None:
        super().__init__(message, status_code=status_code, code=code, details=details)
        self.errors: list[dict[str, str]] = _validation_items(details)

    def __str__(self) -> str:
        if not self.errors:
            return self.message
        lines = [self.message] + [f"  {e['path'] or '(scene)'}: {e['message']}" for e in self.errors]
        return "\n".join(lines)


class Unauthorized(ApiError):
    """A token is missing or wrong (401/403)."""


class NotFound(ApiError):
    """No such job or example, or it belongs to another caller (404)."""


class Conflict(ApiError):
    """The job is not in a state that allows this (409): cancel a finished job, a result not there yet."""


class TooLarge(ApiError):
    """The request or the scene it implies is over the service's limits (413)."""


class QuotaExceeded(ApiError):
    """Too many jobs for this caller right now (429)."""


class ServiceUnavailable(ApiError):
    """The service cannot be reached or is not ready (connection error, 502/503/504), after retries."""


class JobFailed(MpmError):
    """A job ended without succeeding; ``diagnostic`` is the solver's message."""

    def __init__(self, job_id: str, status: str, diagnostic: str | None) -> None:
        self.job_id = job_id
        self.status = status
        self.diagnostic = diagnostic
        text = f"job {job_id} {status}"
        super().__init__(f"{text}: {diagnostic}" if diagnostic else text)


class JobCancelled(JobFailed):
    """The job was cancelled before it finished (its partial result may still be downloaded)."""


class WaitTimeout(MpmError, TimeoutError):
    """``Job.wait(timeout=...)`` ran out of time; the job keeps running."""


_BY_STATUS: dict[int, type[ApiError]] = {
    401: Unauthorized,
    403: Unauthorized,
    404: NotFound,
    409: Conflict,
    413: TooLarge,
    422: ValidationFailed,
    429: QuotaExceeded,
    502: ServiceUnavailable,
    503: ServiceUnavailable,
    504: ServiceUnavailable,
}


def error_from_response(response: httpx.Response) -> ApiError:
    """The typed error for an error response (status >= 400); the body must already be read."""
    code, message, details = None, None, None
    try:
        body = response.json()
    except ValueError:
        body = None
    if isinstance(body, dict) and isinstance(body.get("error"), dict):
        error = body["error"]
        code, message, details = error.get("code"), error.get("message"), error.get("details")
    elif isinstance(body, dict) and "detail" in body:  # a framework default error body
        details = body["detail"]
    if not message:
        message = f"{response.request.method} {response.request.url.path} answered {response.status_code} {response.reason_phrase}"
    cls = _BY_STATUS.get(response.status_code, ApiError)
    return cls(message, status_code=response.status_code, code=code, details=details)


def _validation_items(details: Any) -> list[dict[str, str]]:
    """``[{"path", "message"}]`` from the details of a 422 (tolerates a FastAPI default body)."""
    if not isinstance(details, list):
        return []
    items = []
    for item in details:
        if not isinstance(item, dict):
            continue
        path = item.get("path")
        if path is None and isinstance(item.get("loc"), list):
            path = ".".join(str(part) for part in item["loc"])
        items.append({"path": str(path or ""), "message": str(item.get("message") or item.get("msg") or "")})
    return items
