"""A one-line progress bar for ``Job.wait``: percent, sim time, steps/s and ETA.

Written here rather than taken from tqdm/rich so the SDK stays httpx + pydantic.
On a terminal the line is redrawn in place; otherwise (a log file, CI) a plain
line is printed when the status changes and at most every ``log_interval`` seconds.
"""
from __future__ import annotations

import shutil
import sys
import time
from typing import TextIO

from .models import JobRecord


def format_duration(seconds: float | None) -> str:
    """``75`` -> ``"1:15"``, ``3725`` -> ``"1:02:05"``; ``"?"`` when unknown."""
    if seconds is None or seconds != seconds or seconds < 0:
        return "?"
    whole = int(round(seconds))
    hours, rest = divmod(whole, 3600)
    minutes, secs = divmod(rest, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


def format_progress(record: JobRecord, width: int = 24) -> str:
    """The progress line of a job record, e.g. ``[######------]  45.0%  t 1.575/3.5  812 steps/s  ETA 0:12  running``."""
    fraction = min(max(record.progress or 0.0, 0.0), 1.0)
    filled = int(round(fraction * width))
    parts = [f"[{'#' * filled}{'-' * (width - filled)}]", f"{fraction * 100:5.1f}%"]
    end = f"/{record.end_time:g}" if record.end_time is not None else ""
    parts.append(f"t {record.sim_time:.4g}{end}")
    if record.steps_per_second:
        parts.append(f"{record.steps_per_second:,.0f} steps/s")
    if record.status == "running":
        parts.append(f"ETA {format_duration(record.eta_seconds)}")
    parts.append(f"running ({record.stage})" if record.status == "running" and record.stage else record.status)
    return "  ".join(parts)


class ProgressBar:
    """Shows successive job records on ``stream`` (stderr by default)."""

    def __init__(self, stream: TextIO | None = None, *, width: int = 24, log_interval: float = 10.0) -> None:
        self.stream = stream if stream is not None else sys.stderr
        self.width = width
        self.log_interval = log_interval
        self._tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self._last_status: str | None = None
        self._last_log = 0.0
        self._drawn = 0

    def update(self, record: JobRecord) -> None:
        columns = shutil.get_terminal_size().columns if self._tty else 120
        progress = format_progress(record, self.width)
        overflow = len(progress) + 11 - columns  # leave room for at least 8 characters of the name
        if overflow > 0:  # a narrow terminal: a shorter bar
            progress = format_progress(record, max(6, self.width - overflow))
        name = _shorten(record.name or record.id[:8], min(32, max(8, columns - len(progress) - 3)))
        line = f"{name}  {progress}"
        if self._tty:
            # one terminal line (a wrapped line cannot be redrawn), padded over the previous one
            line = line[:columns - 1]
            self.stream.write("\r" + line.ljust(self._drawn))
            self._drawn = len(line)
        else:
            now = time.monotonic()
            if record.status != self._last_status or now - self._last_log >= self.log_interval:
                self.stream.write(line + "\n")
                self._last_log = now
        self._last_status = record.status
        self.stream.flush()

    def close(self) -> None:
        if self._tty and self._drawn:
            self.stream.write("\n")
            self.stream.flush()
        self._drawn = 0


def _shorten(text: str, width: int) -> str:
    return text if len(text) <= width else text[:width - 1] + "…"
