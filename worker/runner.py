"""Run the solver in a child process: `python -m solver run scene.json -o DIR --progress json -n K`.

The child gets its own process group, so that a stop reaches the whole group
(`mpiexec` and its ranks too) and a Ctrl-C at the terminal of `mpm serve` does
not. A stop is SIGTERM (the solver finishes its step and closes the result file
as partial), then SIGKILL after a grace period. Progress lines are forwarded at
a bounded rate: the latest one at most every `progress_interval` seconds.
"""
from __future__ import annotations

import json
import os
import queue
import signal
import subprocess
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from core.processes import die_with_parent

# One JSON object per progress line; lines that are not JSON go to the log.
ProgressLine = dict[str, Any]


@dataclass
class Outcome:
    returncode: int
    done: ProgressLine | None  # the solver's last line, {"event": "done", ...Result}
    stopped: str | None         # why we stopped it ("cancelled", "timeout", "shutdown"), or None
    log_tail: str               # the end of the solver's stderr, for diagnostics
    lost_why: str | None = None  # a run lost through no fault of its own (worker/slurm.py): why


@dataclass(frozen=True)
class RunControl:
    """What the task gives a launcher's run (worker/launcher.py): where its progress lines go
    (the latest at most every `progress_interval` seconds), what it polls for a reason to stop,
    its time limit and the solver's environment."""
    on_progress: Callable[[ProgressLine], None]
    should_stop: Callable[[], str | None]
    progress_interval: float = 0.5
    timeout_seconds: float | None = None
    env: dict[str, str] | None = None


def solver_command(scene: Path, out_dir: Path, processes: int = 1, progress: str = "json",
                   checkpoint_seconds: float | None = None) -> list[str]:
    """With `checkpoint_seconds`: checkpoints that often, and a run that goes on from the
    checkpoint in `out_dir` when there is one (a job run again after a crash).

    -n: the processes granted, whatever the scene asks; for K > 1 the solver turns
    itself into mpiexec with K ranks (same pid, same process group)."""
    command = [sys.executable, "-m", "solver", "run", str(scene), "-o", str(out_dir),
               "--progress", progress, "-n", str(processes)]
    if checkpoint_seconds is not None:
        command += ["--resume", str(out_dir), "--checkpoint-seconds", repr(checkpoint_seconds)]
    return command


def _kill_group(process: subprocess.Popen, sig: int) -> None:
    try:
        os.killpg(process.pid, sig)
    except ProcessLookupError:
        pass


def progress_item(raw: str) -> ProgressLine | None:
    """A line of the solver's output as its JSON object, or None for a line that is not one (log text)."""
    try:
        item = json.loads(raw)
    except ValueError:
        return None
    return item if isinstance(item, dict) else None


def _read_lines(stream, lines: queue.Queue, log) -> None:
    for raw in stream:
        item = progress_item(raw)
        if item is not None:
            lines.put(item)
            if item.get("event") == "done":  # the run's last word goes to its log too (GET .../log),
                # with the result's name, not the server's path to it
                shown = {**item, **{key: Path(item[key]).name for key in ("result_path",) if key in item}}
                shown.pop("out_dir", None)
                log.write(json.dumps(shown) + "\n")
                log.flush()
        elif raw.strip():
            log.write(raw)
            log.flush()
    lines.put(None)  # end of output


def tail(path: Path, chars: int = 2000) -> str:
    try:
        with open(path, "rb") as f:
            f.seek(max(0, f.seek(0, os.SEEK_END) - chars))
            return f.read().decode(errors="replace").strip()
    except OSError:
        return ""


def run_solver(command: list[str], log_path: Path, *,
               on_progress: Callable[[ProgressLine], None],
               should_stop: Callable[[], str | None],
               progress_interval: float = 0.5,
               poll_interval: float = 0.25,
               grace_seconds: float = 10.0,
               timeout_seconds: float | None = None,
               env: dict[str, str] | None = None) -> Outcome:
    """Run `command` to its end, or until `should_stop()` names a reason to stop it.

    `should_stop` is polled every `poll_interval` seconds until the command has exited;
    `on_progress` receives the solver's progress lines, the latest at most every
    `progress_interval` seconds."""
    lines: queue.Queue = queue.Queue()
    done: ProgressLine | None = None
    pending: ProgressLine | None = None
    last_sent = 0.0
    stopped: str | None = None
    term_sent_at: float | None = None
    started = time.monotonic()
    with open(log_path, "a", encoding="utf-8") as log:
        process = subprocess.Popen(command, stdout=subprocess.PIPE, stderr=log, text=True,
                                   start_new_session=True, preexec_fn=die_with_parent,
                                   cwd=log_path.parent, env=env)
        reader = threading.Thread(target=_read_lines, args=(process.stdout, lines, log), daemon=True)
        reader.start()
        output_open = True
        next_poll = 0.0
        try:
            while output_open or process.poll() is None:
                try:
                    item = lines.get(timeout=poll_interval)
                except queue.Empty:
                    item = False
                if item is None:
                    output_open = False
                elif item:
                    if item.get("event") == "done":
                        done = item
                    else:
                        pending = item
                now = time.monotonic()
                if pending is not None and now - last_sent >= progress_interval:
                    on_progress(pending)
                    pending, last_sent = None, now
                if now >= next_poll:
                    next_poll = now + poll_interval
                    # Polled to the end, a stop's grace period included: it renews the job's lease.
                    reason = should_stop()
                    if stopped is None:
                        stopped = reason
                        if stopped is None and timeout_seconds and now - started > timeout_seconds:
                            stopped = "timeout"
                        if stopped is not None:
                            _kill_group(process, signal.SIGTERM)
                            term_sent_at = now
                    if reason == "lease_lost":  # the folder is another run's now: no last write
                        stopped = reason
                        _kill_group(process, signal.SIGKILL)
                    elif term_sent_at is not None and now - term_sent_at > grace_seconds:
                        _kill_group(process, signal.SIGKILL)
                        term_sent_at = None
        finally:
            if process.poll() is None:  # an exception above: leave no solver behind
                _kill_group(process, signal.SIGKILL)
            process.wait()
            reader.join(timeout=5)
    if pending is not None:
        on_progress(pending)
    return Outcome(process.returncode, done, stopped, tail(log_path))
