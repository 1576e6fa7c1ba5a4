"""Service benchmarks: queue latency, status-read latency under load, job throughput.

    python benchmarks/service.py            # about 2 minutes; prints a markdown table

It starts its own stack on free ports with a temporary MPM_DATA_DIR: an embedded
Redis, two workers (`mpm worker`) and the API (`mpm serve --no-worker`),
and stops it at the end. Measured:

1. submit -> running with an idle, warm worker (server timestamps: created_at ->
   started_at), and the gap between a worker finishing a job and starting the next
   queued one (finished_at -> started_at);
2. `GET /v1/jobs/{id}` latency at a fixed 200 requests/s for 30 s (open loop:
   latency counts from the scheduled send time, so a stall is not hidden), while
   the job it reads is running;
3. jobs per minute for 100 tiny jobs on 2 workers, and that none is lost.
"""
from __future__ import annotations

import argparse
import asyncio
import contextlib
import os
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from datetime import datetime
from pathlib import Path
from typing import Iterator

import httpx

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from core.models import FINISHED  # noqa: E402
from service.embedded_redis import EmbeddedRedis  # noqa: E402


def scene(name: str, end: float, walls: bool = True) -> dict:
    """The two-disks scene (224 particles, dt 1e-3) between slip walls."""
    disk = {"material": "rubber", "particles_per_cell": 2}
    return {
        "version": 1, "name": name, "dimension": 2,
        "grid": {"lower": [-0.5, -0.5], "upper": [0.5, 0.5], "cell_size": 0.05},
        "materials": {"rubber": {"model": "linear_elastic", "density": 1000,
                                 "youngs_modulus": 1000, "poisson_ratio": 0.3}},
        "bodies": [
            {**disk, "name": "disk1", "geometry": {"type": "sphere", "center": [-0.2, -0.2], "radius": 0.15},
             "initial_velocity": [0.1, 0.1]},
            {**disk, "name": "disk2", "geometry": {"type": "sphere", "center": [0.2, 0.2], "radius": 0.15},
             "initial_velocity": [-0.1, -0.1]},
        ],
        "boundary_conditions": [{"type": "wall", "face": f, "mode": "slip"} for f in ("x-", "x+", "y-", "y+")]
        if walls else [],
        "time": {"end": end, "dt": 0.001},
        "output": {"frames": 3},
    }


def seconds_between(start: str, end: str) -> float:
    parse = lambda text: datetime.fromisoformat(text.replace("Z", "+00:00"))  # noqa: E731
    return (parse(end) - parse(start)).total_seconds()


def percentile(values: list[float], q: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(round(q / 100 * (len(ordered) - 1))))]


class Stack:
    """Redis, two workers (`processes[0:2]`) and the API (`processes[2]`); `env` adds settings."""

    def __init__(self, data_dir: Path, env: dict[str, str] | None = None):
        self.redis = EmbeddedRedis(data_dir).start()
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            port = s.getsockname()[1]
        self.url = f"http://127.0.0.1:{port}"
        self.env = {**os.environ, "MPM_REDIS_URL": self.redis.url, "MPM_DATA_DIR": str(data_dir),
                    "MPM_LOG_LEVEL": "WARNING", "MPM_MAX_CONCURRENT_JOBS": "1000", **(env or {})}
        self.logs = open(data_dir / "stack.log", "ab")
        self.processes = [self.start("worker", "--name", "bench1@local"),
                          self.start("worker", "--name", "bench2@local"),
                          self.start("serve", "--no-worker", "--port", str(port))]
        deadline = time.monotonic() + 600
        while time.monotonic() < deadline:
            try:
                ready = httpx.get(self.url + "/readyz", timeout=2)
                if ready.status_code == 200 and ready.json()["workers"] == 2:
                    return
            except httpx.TransportError:
                pass
            time.sleep(0.5)
        self.stop()
        raise RuntimeError(f"the stack did not start; see {data_dir / 'stack.log'}")

    def start(self, *args: str) -> subprocess.Popen:
        """`mpm ARGS` (`python -m solver` is the `mpm` command) with the stack's settings."""
        return subprocess.Popen([sys.executable, "-m", "solver", *args], env=self.env, cwd=ROOT,
                                stdout=self.logs, stderr=self.logs, start_new_session=True)

    def stop(self) -> None:
        for process in self.processes:
            process.send_signal(signal.SIGTERM)
        for process in self.processes:
            try:
                process.wait(60)
            except subprocess.TimeoutExpired:
                process.kill()
        self.redis.stop()


@contextlib.contextmanager
def temporary_stack(stack_class: type[Stack] = Stack, prefix: str = "mpm-bench-") -> Iterator[Stack]:
    """A stack (``stack_class``) on a temporary data folder: stopped after the block, the folder removed."""
    with tempfile.TemporaryDirectory(prefix=prefix) as tmp:
        stack = stack_class(Path(tmp))
        try:
            yield stack
        finally:
            stack.stop()


def submit(api: httpx.Client, body: dict) -> str:
    answer = api.post("/v1/jobs", json={"scene": body})
    answer.raise_for_status()
    return answer.json()["id"]


def wait(api: httpx.Client, job_id: str, statuses=FINISHED, timeout: float = 600) -> dict:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        record = api.get(f"/v1/jobs/{job_id}").json()
        if record["status"] in statuses:
            return record
        time.sleep(0.05)
    raise TimeoutError(f"job {job_id} did not reach {statuses}")


def queue_latency(api: httpx.Client, rounds: int) -> dict:
    to_running, handover = [], []
    for i in range(rounds):
        job = wait(api, submit(api, scene(f"latency{i}", end=0.05)))
        to_running.append(seconds_between(job["created_at"], job["started_at"]))
    for i in range(rounds // 2):
        # both workers busy, a third job queued: it starts when the first of them is free
        busy = [submit(api, scene(f"busy{i}-{k}", end=5.0)) for k in range(2)]
        for job_id in busy:
            wait(api, job_id, ("running",) + FINISHED)
        queued = submit(api, scene(f"queued{i}", end=0.05))
        finished = [wait(api, job_id) for job_id in busy]
        started = wait(api, queued)["started_at"]
        handover.append(seconds_between(min(f["finished_at"] for f in finished), started))
    return {"to_running": to_running, "handover": handover}


async def _connection(host: str, port: int, path: str, due: asyncio.Queue, latencies: list[float],
                      failures: list[str]) -> None:
    """One keep-alive HTTP/1.1 connection sending the scheduled requests it takes from `due`.

    A minimal client on purpose: the load generator shares the machine with the
    server, and a full HTTP client would cost more CPU per request than the server."""
    reader, writer = await asyncio.open_connection(host, port)
    request = f"GET {path} HTTP/1.1\r\nHost: {host}\r\n\r\n".encode()
    try:
        while (scheduled := await due.get()) is not None:
            writer.write(request)
            head = await reader.readuntil(b"\r\n\r\n")
            status = int(head.split(b" ", 2)[1])
            length = next(int(line.split(b":", 1)[1]) for line in head.split(b"\r\n")
                          if line.lower().startswith(b"content-length:"))
            await reader.readexactly(length)
            latencies.append(time.perf_counter() - scheduled)
            if status != 200:
                failures.append(str(status))
    except (OSError, asyncio.IncompleteReadError, ValueError) as exc:
        failures.append(repr(exc))
    finally:
        writer.close()


async def status_load(url: str, job_id: str, rate: float, seconds: float, connections: int = 32) -> dict:
    """Open loop: requests are due at a fixed rate whether or not earlier ones were answered,
    and each latency counts from the time the request was due (a stall is not hidden)."""
    host, port = url.removeprefix("http://").split(":")
    due: asyncio.Queue = asyncio.Queue()
    latencies: list[float] = []
    failures: list[str] = []
    workers = [asyncio.create_task(_connection(host, int(port), f"/v1/jobs/{job_id}", due, latencies, failures))
               for _ in range(connections)]
    count = int(rate * seconds)
    start = time.perf_counter() + 0.2
    for k in range(count):
        scheduled = start + k / rate
        delay = scheduled - time.perf_counter()
        if delay > 0:
            await asyncio.sleep(delay)
        due.put_nowait(scheduled)
    for _ in workers:
        due.put_nowait(None)
    await asyncio.gather(*workers)
    elapsed = time.perf_counter() - start
    return {"latencies": latencies, "errors": len(failures) + count - len(latencies), "requests": count,
            "achieved_rate": len(latencies) / elapsed}


def throughput(api: httpx.Client, jobs: int) -> dict:
    started = time.monotonic()
    ids = [submit(api, scene(f"tiny{i}", end=0.05)) for i in range(jobs)]
    finals = [wait(api, job_id) for job_id in ids]
    elapsed = time.monotonic() - started
    succeeded = sum(f["status"] == "succeeded" for f in finals)
    return {"jobs": jobs, "seconds": elapsed, "per_minute": jobs / elapsed * 60,
            "succeeded": succeeded, "lost": jobs - succeeded}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--rate", type=float, default=200.0, help="status requests per second")
    parser.add_argument("--seconds", type=float, default=30.0, help="duration of the status load")
    parser.add_argument("--jobs", type=int, default=100, help="tiny jobs for the throughput")
    parser.add_argument("--rounds", type=int, default=10, help="jobs for the queue latency")
    args = parser.parse_args()

    with temporary_stack() as stack, httpx.Client(base_url=stack.url, timeout=30) as api:
        latency = queue_latency(api, args.rounds)
        target = submit(api, scene("under-load", end=args.seconds * 100))
        wait(api, target, ("running",))
        load = asyncio.run(status_load(stack.url, target, args.rate, args.seconds))
        api.post(f"/v1/jobs/{target}/cancel")
        wait(api, target)
        jobs = throughput(api, args.jobs)

    ms = lambda seconds: f"{seconds * 1000:.0f} ms"  # noqa: E731
    lat = load["latencies"]
    rows = [
        ("submit -> running, idle warm worker (median / max of "
         f"{len(latency['to_running'])})", f"{ms(statistics.median(latency['to_running']))} / "
                                           f"{ms(max(latency['to_running']))}"),
        (f"worker free -> next queued job running (median / max of {len(latency['handover'])})",
         f"{ms(statistics.median(latency['handover']))} / {ms(max(latency['handover']))}"),
        (f"GET /v1/jobs/{{id}} at {args.rate:.0f} req/s for {args.seconds:.0f} s, job running: p50 / p99 / max",
         f"{ms(percentile(lat, 50))} / {ms(percentile(lat, 99))} / {ms(max(lat))}"),
        ("  requests, errors, achieved rate",
         f"{load['requests']}, {load['errors']}, {load['achieved_rate']:.0f} req/s"),
        (f"{jobs['jobs']} tiny jobs (50 steps) on 2 workers", f"{jobs['per_minute']:.0f} jobs/min "
                                                              f"({jobs['seconds']:.1f} s)"),
        ("  succeeded, lost", f"{jobs['succeeded']}, {jobs['lost']}"),
    ]
    print("| measurement | result |\n|---|---|")
    for name, value in rows:
        print(f"| {name} | {value} |")
    return 0 if load["errors"] == 0 and jobs["lost"] == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
