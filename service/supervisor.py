"""What `mpm serve` keeps running: its worker and its embedded Redis are started again
when they die (killed, out of memory, a crash), by a thread that looks at them every
second. One that dies again soon after a start waits longer before the next start
(1 s, doubling to a minute), so that a process that cannot start does not spin."""
from __future__ import annotations

import logging
import signal
import subprocess
import threading
import time
from dataclasses import dataclass
from typing import Callable

from core.processes import die_with_parent

log = logging.getLogger("mpm.serve")

CHECK_EVERY = 1.0
FIRST_DELAY, MAX_DELAY = 1.0, 60.0
# A process alive this long after its start counts as healthy again (the delay resets).
HEALTHY_AFTER = 60.0


class ChildProcess:
    """A command run in its own session (a Ctrl-C reaches `mpm serve` only, which stops
    it in order), ended with its parent (PR_SET_PDEATHSIG)."""

    def __init__(self, command: list[str], env: dict[str, str]):
        self.command, self.env = command, env
        self.popen: subprocess.Popen | None = None

    def start(self) -> "ChildProcess":
        self.popen = subprocess.Popen(self.command, env=self.env, start_new_session=True,
                                      preexec_fn=die_with_parent)
        return self

    def alive(self) -> bool:
        return self.popen is not None and self.popen.poll() is None

    def stop(self, timeout: float) -> None:
        """SIGTERM (a worker requeues its running job), SIGKILL after `timeout`."""
        if not self.alive():
            return
        self.popen.send_signal(signal.SIGTERM)
        try:
            self.popen.wait(timeout)
        except subprocess.TimeoutExpired:
            log.warning("process did not stop in time; killed", extra={"pid": self.popen.pid})
            self.popen.kill()
            self.popen.wait()


@dataclass
class _Watched:
    name: str
    alive: Callable[[], bool]
    restart: Callable[[], object]
    started: float
    delay: float = FIRST_DELAY
    died_at: float | None = None


class Supervisor:
    def __init__(self):
        self._watched: list[_Watched] = []
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="mpm-supervisor", daemon=True)
        self.restarts = 0

    def watch(self, name: str, alive: Callable[[], bool], restart: Callable[[], object]) -> None:
        self._watched.append(_Watched(name, alive, restart, time.monotonic()))

    def start(self) -> "Supervisor":
        self._thread.start()
        return self

    def stop(self) -> None:
        """Before stopping the processes themselves: nothing is restarted after this."""
        self._stop.set()
        if self._thread.is_alive():
            self._thread.join()

    def _run(self) -> None:
        while not self._stop.wait(CHECK_EVERY):
            for item in self._watched:
                self._check(item)

    def _check(self, item: _Watched) -> None:
        now = time.monotonic()
        if item.alive():
            if now - item.started > HEALTHY_AFTER:
                item.delay = FIRST_DELAY
            return
        if item.died_at is None:
            item.died_at = now
            log.warning("%s died; starting it again in %.0f s", item.name, item.delay)
        if now - item.died_at < item.delay or self._stop.is_set():
            return
        try:
            item.restart()
        except Exception as exc:  # noqa: BLE001 - logged, tried again after the next delay
            log.error("%s did not start again: %s", item.name, exc)
        else:
            log.info("%s started again", item.name)
            self.restarts += 1
        item.started, item.died_at = time.monotonic(), None
        item.delay = min(MAX_DELAY, item.delay * 2)
