"""What the integration tests share: the processes of the stack, waiting helpers,
and small scenes (a second or two of solver time each).

The processes' logs go to files under the session's temporary folder; a failing
start prints their tails."""
from __future__ import annotations

import contextlib
import copy
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path
from typing import Any, Callable, Iterator

import httpx
import redis

from core.models import FINISHED
from core.store import JobStore
from service.embedded_redis import EmbeddedRedis

# The `mpm` command (`python -m solver` is the same dispatcher), as users run it.
MPM = [sys.executable, "-m", "solver"]


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Process:
    """A child process with its output in a log file; stopped with SIGTERM, then SIGKILL."""

    def __init__(self, name: str, command: list[str], env: dict[str, str], log_dir: Path):
        self.name, self.command, self.env = name, command, env
        self.log = log_dir / f"{name}.log"
        self.popen: subprocess.Popen | None = None

    def start(self) -> "Process":
        out = open(self.log, "ab")
        self.popen = subprocess.Popen(self.command, env=self.env, stdout=out, stderr=subprocess.STDOUT,
                                      stdin=subprocess.DEVNULL, start_new_session=True)
        out.close()
        return self

    def alive(self) -> bool:
        return self.popen is not None and self.popen.poll() is None

    def signal(self, sig: int) -> None:
        if self.alive():
            self.popen.send_signal(sig)

    def stop(self, timeout: float = 30) -> int | None:
        if self.popen is None:
            return None
        self.signal(signal.SIGTERM)
        try:
            return self.popen.wait(timeout)
        except subprocess.TimeoutExpired:
            os.killpg(self.popen.pid, signal.SIGKILL)
            return self.popen.wait()

    def tail(self, chars: int = 3000) -> str:
        return self.log.read_text(errors="replace")[-chars:] if self.log.exists() else ""


def wait_until(predicate: Callable[[], Any], timeout: float, what: str, interval: float = 0.1,
               processes: tuple[Process, ...] = ()) -> Any:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        for p in processes:
            if not p.alive():
                raise AssertionError(f"{p.name} exited ({p.popen.returncode}) waiting for {what}:\n{p.tail()}")
        time.sleep(interval)
    logs = "\n".join(f"--- {p.name}\n{p.tail()}" for p in processes)
    raise AssertionError(f"timed out after {timeout} s waiting for {what}\n{logs}")


def answers(url: str, path: str, status: int = 200) -> Callable[[], bool]:
    def check() -> bool:
        try:
            return httpx.get(url + path, timeout=2).status_code == status
        except httpx.TransportError:
            return False
    return check


def processes_with(text: str) -> list[int]:
    """Live processes whose command line contains `text` (Linux /proc)."""
    found = []
    for entry in Path("/proc").iterdir():
        try:
            if entry.name.isdigit() and text in (entry / "cmdline").read_bytes().decode(errors="ignore"):
                if (entry / "stat").read_text().rsplit(")", 1)[1].split()[0] != "Z":
                    found.append(int(entry.name))
        except OSError:
            continue
    return found


WEBHOOK_SECRET = "test-webhook-secret"  # MPM_WEBHOOK_SECRET of the integration stack


class Stack:
    """Redis + two workers + the API (`mpm serve --no-worker`), sharing one data dir."""

    def __init__(self, redis_server: EmbeddedRedis, data_dir: Path, log_dir: Path):
        self.redis_url = redis_server.url
        self.data_dir = data_dir
        self.log_dir = log_dir
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.env = {**os.environ, "MPM_REDIS_URL": self.redis_url, "MPM_DATA_DIR": str(data_dir),
                    "MPM_PROGRESS_INTERVAL": "0.2", "MPM_CANCEL_GRACE_SECONDS": "5",
                    "MPM_LEASE_SECONDS": "3",
                    "MPM_MAX_PARTICLES": "80000", "MPM_MAX_STEPS": "5000000",
                    "MPM_MAX_BODY_BYTES": "100000",
                    "MPM_MAX_CONCURRENT_JOBS": "40", "MPM_MAX_PROCESSES": "2", "PYTHONUNBUFFERED": "1",
                    # the anonymous caller's quotas above MPM_MAX_CONCURRENT_JOBS, whose test this is
                    "MPM_QUOTA_QUEUED_JOBS": "100", "MPM_QUOTA_ACTIVE_JOBS": "100",
                    "MPM_WEBHOOK_SECRET": WEBHOOK_SECRET}
        self.workers = [self._worker_process(1, warmup=True),
                        # the first worker fills the shared on-disk kernel cache
                        self._worker_process(2, warmup=False)]
        self.api = self._api_process()
        self.store = JobStore(redis.Redis.from_url(self.redis_url, decode_responses=True))

    def _worker_process(self, number: int, warmup: bool) -> Process:
        command = [*MPM, "worker", "--name", f"w{number}@test"]
        return Process(f"worker{number}", command + ([] if warmup else ["--no-warmup"]),
                       self.env, self.log_dir)

    def restart_worker(self, name: str) -> None:
        """Start again the worker called `name` (after a test stopped or killed it)."""
        number = int(name.split("@")[0][1:])
        self.workers[number - 1] = self._worker_process(number, warmup=False).start()
        wait_until(lambda: len(self.store.live_workers(10)) == 2, 60, f"worker {name} back",
                   processes=(self.workers[number - 1],))

    def _api_process(self) -> Process:
        return Process("api", [*MPM, "serve", "--no-worker", "--port", str(self.port)],
                       self.env, self.log_dir)

    def start(self) -> "Stack":
        for worker in self.workers:
            worker.start()
        self.start_api()
        wait_until(lambda: len(self.store.live_workers(10)) == 2, 600, "two workers (after warm-up)",
                   interval=0.5, processes=(*self.workers, self.api))
        wait_until(answers(self.url, "/readyz"), 20, "/readyz", processes=(self.api,))
        return self

    @contextlib.contextmanager
    def running(self) -> Iterator["Stack"]:
        """The stack started for the block and stopped after it (also when it failed to start:
        the processes that did start are stopped)."""
        try:
            yield self.start()
        finally:
            self.stop()

    def api_client(self) -> httpx.Client:
        """A client of the stack's API, for a test's `api` fixture."""
        return httpx.Client(base_url=self.url, timeout=30)

    def start_api(self) -> None:
        self.api = self._api_process().start()
        wait_until(answers(self.url, "/healthz"), 60, "the API", processes=(self.api,))

    def stop(self) -> None:
        self.api.stop()
        for worker in self.workers:
            worker.signal(signal.SIGTERM)
        for worker in self.workers:
            worker.stop()
        self.store.redis.close()


def wait_for_status(api: httpx.Client, job_id: str, statuses: tuple[str, ...] = FINISHED,
                    timeout: float = 120) -> dict:
    """Poll the job until its status is one of `statuses`; returns the record."""
    last: dict = {}

    def reached() -> bool:
        nonlocal last
        last = api.get(f"/v1/jobs/{job_id}").json()
        return last["status"] in statuses

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if reached():
            return last
        time.sleep(0.1)
    raise AssertionError(f"job {job_id} did not reach {statuses} in {timeout} s: {last}")


TWO_DISKS: dict[str, Any] = {
    "version": 1, "name": "two-disks", "dimension": 2,
    "grid": {"lower": [-0.5, -0.5], "upper": [0.5, 0.5], "cell_size": 0.05},
    "materials": {"rubber": {"model": "linear_elastic", "density": 1000,
                             "youngs_modulus": 1000, "poisson_ratio": 0.3}},
    "bodies": [
        {"name": "disk1", "material": "rubber", "particles_per_cell": 2,
         "geometry": {"type": "sphere", "center": [-0.2, -0.2], "radius": 0.15},
         "initial_velocity": [0.1, 0.1]},
        {"name": "disk2", "material": "rubber", "particles_per_cell": 2,
         "geometry": {"type": "sphere", "center": [0.2, 0.2], "radius": 0.15},
         "initial_velocity": [-0.1, -0.1]},
    ],
    "time": {"end": 1.0, "dt": 0.001},
    "output": {"frames": 6, "fields": ["position", "velocity", "stress", "velocity_magnitude"]},
}


def two_disks(name: str = "two-disks", end: float = 1.0, dt: float = 0.001) -> dict[str, Any]:
    scene = copy.deepcopy(TWO_DISKS)
    scene["name"] = name
    scene["time"] = {"end": end, "dt": dt}
    return scene


def boxed(name: str, end: float) -> dict[str, Any]:
    """The two disks between slip walls: stable however long it runs (about 15000 steps/s here)."""
    scene = two_disks(name, end=end)
    scene["boundary_conditions"] = [{"type": "wall", "face": face, "mode": "slip"}
                                    for face in ("x-", "x+", "y-", "y+")]
    return scene


def long_running(name: str = "long") -> dict[str, Any]:
    """Minutes of steps: long enough to be cancelled or interrupted while running."""
    return boxed(name, end=3000.0)


def unstable(name: str = "unstable") -> dict[str, Any]:
    """A time step fifty times too large: the disks blow up and leave the grid."""
    scene = two_disks(name, end=5.0, dt=0.05)
    scene["time"]["allow_unstable_dt"] = True   # validation refuses it otherwise (solver/stability.py)
    return scene


def bar_1d(name: str, end: float, frames: int = 2, model: str = "linear_elastic",
           particles_per_cell: int = 2) -> dict[str, Any]:
    """An elastic bar on a 1D grid of 8 cells, moving at 0.1 m/s: the smallest job there is
    (thousands of its 1 ms steps a second here)."""
    return {"version": 1, "name": name, "dimension": 1,
            "grid": {"lower": [0.0], "upper": [1.0], "cell_size": 0.125},
            "materials": {"m": {"model": model, "density": 1000.0, "youngs_modulus": 1000.0,
                                "poisson_ratio": 0.3}},
            "bodies": [{"name": "b", "material": "m", "geometry": {"type": "box", "lower": [0.25], "upper": [0.75]},
                        "particles_per_cell": particles_per_cell, "initial_velocity": [0.1]}],
            "time": {"end": end, "dt": 0.001}, "output": {"frames": frames}}
