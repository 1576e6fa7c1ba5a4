"""A single-line terminal progress bar for ``mpm run`` (no dependencies).

On a terminal the line is redrawn in place (``\\r``) at most 4 times a second::

    [##########----------]  50.0%  step 1750  t 1.75/3.5  2104 steps/s  ETA 0:01

When the output is not a terminal (a log file, CI) a plain line is printed
every few seconds instead. :meth:`ProgressBar.close` prints the last state and
ends the line.
"""
from __future__ import annotations

import math
import shutil
import sys
import time
from typing import Any, TextIO

BAR_WIDTH = 24


def format_duration(seconds: float | None) -> str:
    """``75 -> "1:15"``, ``3725 -> "1:02:05"``; ``"?"`` when unknown."""
    if seconds is None or not math.isfinite(seconds) or seconds < 0:
        return "?"
    minutes, secs = divmod(int(round(seconds)), 60)
    hours, minutes = divmod(minutes, 60)
    return f"{hours}:{minutes:02d}:{secs:02d}" if hours else f"{minutes}:{secs:02d}"


class RateMeter:
    """Recent rates of a run, smoothed: steps and simulated time per wall-clock second.

    The first update only sets the origin: what came before it (loading the kernels,
    compiling a new variant, placing the particles) says nothing about the steps to
    come, and a rate or an ETA taken over it was absurd ("ETA 4:22:43" for a 21 s
    run). Each later interval's rates enter an exponential average over TIME_CONSTANT
    seconds of wall time, so the ETA follows an adaptive step that shrinks or grows.
    The rate is known after one measured interval, the ETA after MIN_SECONDS of them.
    """

    TIME_CONSTANT = 5.0
    MIN_SECONDS = 1.0

    def __init__(self) -> None:
        self._last: tuple[float, int, float] | None = None
        self._steps: float | None = None      # steps per second
        self._sim_time: float | None = None   # simulated time per second
        self._measured = 0.0

    def update(self, now: float, step: int, sim_time: float) -> None:
        if self._last is None:
            self._last = (now, step, sim_time)
            return
        then, last_step, last_time = self._last
        elapsed = now - then
        if elapsed <= 0 or step <= last_step:
            return
        steps, simulated = (step - last_step) / elapsed, (sim_time - last_time) / elapsed
        if self._steps is None:
            self._steps, self._sim_time = steps, simulated
        else:
            weight = 1.0 - math.exp(-elapsed / self.TIME_CONSTANT)
            self._steps += weight * (steps - self._steps)
            self._sim_time += weight * (simulated - self._sim_time)
        self._measured += elapsed
        self._last = (now, step, sim_time)

    @property
    def steps_per_second(self) -> float | None:
        return self._steps

    def eta_seconds(self, remaining_sim_time: float) -> float | None:
        """Wall time to simulate `remaining_sim_time` more at the recent rate; None until known."""
        if self._sim_time is None or self._sim_time <= 0 or self._measured < self.MIN_SECONDS:
            return None
        return max(remaining_sim_time, 0.0) / self._sim_time


class ProgressBar:
    """Draws progress updates (objects or dicts with the ProgressInfo fields).

    Reads ``fraction``, ``step``, ``time``, ``end_time``, ``steps_per_second``
    and ``eta_seconds``.
    """

    def __init__(
        self,
        stream: TextIO | None = None,
        min_interval: float = 0.25,
        plain_interval: float = 5.0,
        clock=time.monotonic,
    ) -> None:
        self.stream = stream or sys.stdout
        self.tty = bool(getattr(self.stream, "isatty", lambda: False)())
        self.interval = min_interval if self.tty else plain_interval
        self.clock = clock
        self._last_draw: float | None = None
        self._last_line = ""
        self._pending: str | None = None

    def update(self, info: Any) -> None:
        """Record an update; draw it unless the last drawing is too recent."""
        line = self.format(info)
        now = self.clock()
        if self._last_draw is not None and now - self._last_draw < self.interval:
            self._pending = line
            return
        self._draw(line)
        self._last_draw = now

    def close(self) -> None:
        """Draw the last state (if not shown yet) and end the line."""
        if self._pending is not None:
            self._draw(self._pending)
        if self.tty and self._last_line:
            self.stream.write("\n")
            self.stream.flush()

    def format(self, info: Any) -> str:
        def get(name: str):
            return info.get(name) if isinstance(info, dict) else getattr(info, name, None)

        fraction = min(max(float(get("fraction") or 0.0), 0.0), 1.0)
        rate, eta = get("steps_per_second"), get("eta_seconds")
        parts = [
            f"{100 * fraction:5.1f}%",
            f"step {get('step') or 0}",
            f"t {float(get('time') or 0.0):.4g}/{float(get('end_time') or 0.0):.4g}",
        ]
        # the rate and the ETA are None until a recent rate is measured (RateMeter): left out until then
        parts += [f"{rate:.0f} steps/s"] if rate else []
        parts += [f"ETA {format_duration(eta)}"] if eta is not None else []
        parts += ["compiling kernels"] if get("stage") == "compiling" else []
        text = "  ".join(parts)
        if not self.tty:
            return text
        filled = int(round(BAR_WIDTH * fraction))
        line = f"[{'#' * filled}{'-' * (BAR_WIDTH - filled)}] {text}"
        return line[: shutil.get_terminal_size((80, 24)).columns - 1]

    def _draw(self, line: str) -> None:
        if self.tty:
            # Pad so a shorter line fully covers the previous one.
            self.stream.write("\r" + line.ljust(len(self._last_line)))
        else:
            self.stream.write(line + "\n")
        self.stream.flush()
        self._last_line = line
        self._pending = None
