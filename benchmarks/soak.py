"""Soak test (not in CI): many small jobs, status polling at a fixed rate, and a
worker killed (kill -9) every minute; nothing may be lost.

    python benchmarks/soak.py                          # the issue's run: 10 minutes, 500 jobs
    python benchmarks/soak.py --minutes 3 --jobs 150   # the shortened run of docs/reliability.md

It starts its own stack on free ports with a temporary MPM_DATA_DIR (the stack of
benchmarks/service.py): an embedded Redis, two workers (`mpm worker`) and the API
(`mpm serve --no-worker`). Jobs are
submitted evenly over the run while `GET /v1/jobs/{id}` is polled at --rate
requests/s (open loop, see benchmarks/service.py); every --kill-every seconds one
worker is killed with SIGKILL and a new one started (what `mpm serve`'s supervisor or
a container restart policy does); half-way through, Redis is killed (SIGKILL) and
started again once (submissions meanwhile are retried, as a client does on 503). At the end it waits for every job and reports
jobs submitted / succeeded / failed / lost, the status-poll latency (p50, p99),
job turnaround, and the resident memory of each long-lived process at start and end.
"""
from __future__ import annotations

import argparse
import asyncio
import json
import importlib.util
import sys
import threading
import time
from pathlib import Path

import httpx

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))


def _service_benchmark():
    """benchmarks/service.py (its name is the service package's): the scene, the open-loop poller."""
    spec = importlib.util.spec_from_file_location("service_benchmark", Path(__file__).with_name("service.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


_bench = _service_benchmark()
FINISHED, percentile, scene, seconds_between, status_load = (
    _bench.FINISHED, _bench.percentile, _bench.scene, _bench.seconds_between, _bench.status_load)


def rss_mib(pid: int) -> float | None:
    try:
        for line in Path(f"/proc/{pid}/status").read_text().splitlines():
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024
    except OSError:
        pass
    return None


class SoakStack(_bench.Stack):
    """benchmarks/service.py's stack (two workers, the API) whose workers are killed and replaced."""

    def __init__(self, data_dir: Path):
        # The anonymous caller's quotas (MPM_QUOTA_*) apply here too: raised for the soak's backlog.
        super().__init__(data_dir, {"MPM_MAX_CONCURRENT_JOBS": "100000", "MPM_LEASE_SECONDS": "6",
                                    "MPM_CHECKPOINT_SECONDS": "2", "MPM_QUOTA_ACTIVE_JOBS": "100000",
                                    "MPM_QUOTA_QUEUED_JOBS": "100000",
                                    "MPM_QUOTA_PARTICLE_STEPS_PER_DAY": "1e18"})
        self.workers, self.api = self.processes[:2], self.processes[2]
        self.started_workers = len(self.workers)

    def memory(self) -> dict[str, float | None]:
        out = {"api": rss_mib(self.api.pid), "redis": rss_mib(self.redis.process.pid)}
        out.update({f"worker{k + 1}": rss_mib(w.pid) for k, w in enumerate(self.workers)})
        return out

    def kill_and_replace_worker(self, index: int) -> None:
        """SIGKILL to the worker's process only (its solver gets SIGTERM from the kernel)."""
        victim = self.workers[index]
        victim.kill()
        victim.wait()
        self.started_workers += 1
        self.workers[index] = self.start("worker", "--no-warmup", "--name", f"soak{self.started_workers}@local")
        self.processes = [*self.workers, self.api]

    def kill_and_restart_redis(self) -> None:
        """SIGKILL to Redis, then start it again on its port with its append-only file
        (what `mpm serve`'s supervisor does). The new redis-server is started by a thread
        that lives until the stack stops: it dies with the thread that started it
        (PR_SET_PDEATHSIG), and the thread calling this one ends before the drain."""
        done = threading.Event()

        def keeper() -> None:
            self.redis.process.kill()
            self.redis.process.wait()
            self.redis.restart()
            done.set()
            self.stopped.wait()

        self.stopped = getattr(self, "stopped", threading.Event())
        threading.Thread(target=keeper, name="redis-keeper", daemon=True).start()
        done.wait()

    def stop(self) -> None:
        super().stop()
        if hasattr(self, "stopped"):
            self.stopped.set()


def _post_retrying(api: httpx.Client, path: str, body: dict, tries: int = 60) -> httpx.Response:
    """A client's submission: a 503 (Redis restarting) or a lost connection is retried, 1 s apart."""
    for _ in range(tries - 1):
        try:
            answer = api.post(path, json=body)
            if answer.status_code != 503:
                return answer
        except httpx.TransportError:
            pass
        time.sleep(1.0)
    return api.post(path, json=body)


def soak(stack: SoakStack, minutes: float, jobs: int, rate: float, kill_every: float, end: float,
         drain_seconds: float = 600.0) -> dict:
    duration = minutes * 60.0
    submitted: list[str] = []
    kills = redis_restarts = 0
    stop = threading.Event()
    memory_start = stack.memory()

    def submit_evenly() -> None:
        with httpx.Client(base_url=stack.url, timeout=30) as api:
            start = time.monotonic()
            for k in range(jobs):
                delay = start + k * duration / jobs - time.monotonic()
                if stop.wait(max(0.0, delay)):
                    return
                answer = _post_retrying(api, "/v1/jobs", {"scene": scene(f"soak{k}", end=end)})
                answer.raise_for_status()
                submitted.append(answer.json()["id"])

    def kill_periodically() -> None:
        nonlocal kills, redis_restarts
        started = time.monotonic()
        while not stop.wait(kill_every):
            stack.kill_and_replace_worker(kills % len(stack.workers))
            kills += 1
            if redis_restarts == 0 and time.monotonic() - started >= duration / 2:
                stack.kill_and_restart_redis()  # once, half-way
                redis_restarts += 1

    submitter = threading.Thread(target=submit_evenly)
    killer = threading.Thread(target=kill_periodically)
    submitter.start()
    killer.start()
    while not submitted:
        time.sleep(0.05)
    polls = asyncio.run(status_load(stack.url, submitted[0], rate, duration))
    submitter.join()
    stop.set()
    killer.join()

    finals = {}
    print(f"run over ({kills} kills); waiting for the {len(submitted)} jobs", file=sys.stderr, flush=True)
    with httpx.Client(base_url=stack.url, timeout=30) as api:
        deadline = time.monotonic() + drain_seconds  # a job not finished by then counts as lost
        for job_id in submitted:
            while time.monotonic() < deadline:
                try:
                    record = api.get(f"/v1/jobs/{job_id}")
                except httpx.TransportError:
                    time.sleep(1.0)
                    continue
                if record.status_code == 200 and record.json()["status"] in FINISHED:
                    finals[job_id] = record.json()
                    break
                time.sleep(0.2)
    memory_end = stack.memory()
    turnaround = [seconds_between(j["created_at"], j["finished_at"]) for j in finals.values()]
    return {
        "minutes": minutes, "kills": kills, "redis_restarts": redis_restarts, "submitted": len(submitted),
        "succeeded": sum(j["status"] == "succeeded" for j in finals.values()),
        "failed": sum(j["status"] == "failed" for j in finals.values()),
        "lost": len(submitted) - len(finals),
        "resumed": sum(j.get("lost", 0) > 0 for j in finals.values()),
        "polls": polls["requests"], "poll_errors": polls["errors"], "poll_rate": polls["achieved_rate"],
        "poll_p50_ms": 1000 * percentile(polls["latencies"], 50),
        "poll_p99_ms": 1000 * percentile(polls["latencies"], 99),
        "turnaround_p50_s": percentile(turnaround, 50), "turnaround_p99_s": percentile(turnaround, 99),
        "memory_start": memory_start, "memory_end": memory_end,
    }


def report(r: dict) -> str:
    rows = [
        f"| run | {r['minutes']:g} min, {r['kills']} workers killed (kill -9), Redis killed (kill -9) "
        f"and restarted {r['redis_restarts']} time(s) |",
        f"| jobs submitted / succeeded / failed / lost | {r['submitted']} / {r['succeeded']} / "
        f"{r['failed']} / {r['lost']} |",
        f"| jobs whose run was lost and resumed | {r['resumed']} |",
        f"| status polls | {r['polls']} at {r['poll_rate']:.0f} req/s, {r['poll_errors']} errors |",
        f"| status-poll latency p50 / p99 | {r['poll_p50_ms']:.1f} ms / {r['poll_p99_ms']:.1f} ms |",
        f"| job turnaround (submit to finished) p50 / p99 | {r['turnaround_p50_s']:.1f} s / "
        f"{r['turnaround_p99_s']:.1f} s |",
    ]
    for name in ("api", "redis"):
        start, end = r["memory_start"][name], r["memory_end"][name]
        growth = f"{100 * (end / start - 1):+.0f} %" if start and end else "-"
        rows.append(f"| resident memory of {name}, start -> end | {start or 0:.0f} MiB -> {end or 0:.0f} MiB "
                    f"({growth}) |")
    workers = [k for k in r["memory_end"] if k.startswith("worker")]
    rows.append("| resident memory of the workers at start / at end (new processes) | "
                + ", ".join(f"{r['memory_start'][k] or 0:.0f}" for k in workers) + " MiB / "
                + ", ".join(f"{r['memory_end'][k] or 0:.0f}" for k in workers) + " MiB |")
    return "| quantity | value |\n|---|---|\n" + "\n".join(rows)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--minutes", type=float, default=10.0)
    parser.add_argument("--jobs", type=int, default=500)
    parser.add_argument("--rate", type=float, default=200.0, help="status polls per second")
    parser.add_argument("--kill-every", type=float, default=60.0, help="seconds between worker kills")
    parser.add_argument("--job-seconds", type=float, default=1.0, help="simulated time of each job (dt 1e-3)")
    args = parser.parse_args()
    with _bench.temporary_stack(SoakStack, prefix="mpm-soak-") as stack:
        result = soak(stack, args.minutes, args.jobs, args.rate, args.kill_every, args.job_seconds)
    print(json.dumps(result), file=sys.stderr, flush=True)  # the figures, whatever the report does
    print(report(result))
    return 0 if result["lost"] == 0 and result["failed"] == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
