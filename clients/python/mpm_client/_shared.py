"""What the sync SDK (client.py) and the async one (aio.py) share: a client's connection
settings and retries, a job handle's state, the bookkeeping of ``wait`` between fetches.
Only the I/O (a call, a sleep: awaited or not) differs between the two, so it stays in
each; everything else lives here once."""
from __future__ import annotations

import os
import time
from pathlib import Path
from typing import Any

from . import _api
from .errors import WaitTimeout
from .models import JobRecord
from .progress import ProgressBar


class ClientBase:
    """Where the service is and how its calls are retried; ``http_class`` is httpx.Client
    or httpx.AsyncClient."""

    def __init__(self, base_url: str | None, token: str | None, *, timeout: float, retries: int,
                 backoff: float, transport: Any, http_class: type) -> None:
        self.base_url = _api.resolve_server(base_url)
        self.retries = retries
        self.backoff = backoff
        self._http = http_class(base_url=self.base_url, headers=_api.headers(_api.resolve_token(token)),
                                timeout=timeout, transport=transport)

    def _retrier(self, call: _api.Call) -> _api.Retrier:
        return _api.Retrier(call.method, retries=self.retries, backoff=self.backoff, url=self.base_url)


class JobHandle:
    """A submitted job: ``record`` is the last :class:`JobRecord` fetched."""

    def __init__(self, client: Any, record: JobRecord) -> None:
        self.client = client
        self.record = record
        self._downloaded: Path | None = None

    @property
    def id(self) -> str:
        return self.record.id

    def __repr__(self) -> str:
        # the class's own name: Job(...) for the sync SDK, AsyncJob(...) for the async one
        return (f"{type(self).__name__}({self.id!r}, status={self.record.status!r}, "
                f"progress={self.record.progress:.2f})")

    def _result_on_disk(self, path: str | os.PathLike[str] | None) -> Path | None:
        """The result file ``open`` can read without a download: ``path`` when given, else the
        last download; None when that file is not there."""
        candidate = Path(path) if path is not None else self._downloaded
        return candidate if candidate is not None and candidate.is_file() else None


class JobWait:
    """One ``wait`` of a job: the progress bar and the deadline, checked after each fetch."""

    def __init__(self, job: JobHandle, timeout: float | None, poll: float, progress: bool) -> None:
        self.job, self.timeout, self.poll = job, timeout, poll
        self.bar = ProgressBar() if progress else None
        self.deadline = None if timeout is None else time.monotonic() + timeout

    def pause(self) -> float | None:
        """After a fetch: None once the job has finished, else the seconds until the next fetch.

        Raises :class:`JobFailed` or :class:`JobCancelled` for a job that ended so, and
        :class:`WaitTimeout` past the deadline (the job keeps running)."""
        record = self.job.record
        if self.bar:
            self.bar.update(record)
        if record.finished:
            _api.finished(self.job)
            return None
        if self.deadline is not None and time.monotonic() >= self.deadline:
            raise WaitTimeout(f"job {self.job.id} still {record.status} after {self.timeout} s")
        return self.poll if self.deadline is None else max(0.0, min(self.poll, self.deadline - time.monotonic()))

    def close(self) -> None:
        if self.bar:
            self.bar.close()
