"""Time to first result: how long a run waits on numba before its first step, cold and warm.

    python benchmarks/startup.py                         # the default examples, cold then warm
    python benchmarks/startup.py --examples two_disks elastic_cube_3d --json startup.json
    python benchmarks/startup.py --all                   # every example (long: each compiles from empty)
    python benchmarks/startup.py --all --first-steps     # every example's cold first step only

For each example, in a kernel cache of its own that starts empty (MPM_CACHE_DIR, solver/
kernel_cache.py), the example runs twice as `mpm run` does (`python -m solver run ...
--progress json`): first cold, then warm. Each run gives the seconds from launch to its first
step (its first "stepping" progress line), the kernels compiled and the seconds spent
compiling (the run's `done` line), its wall time and the estimate it started with (the
first progress line's ETA plus its time: `mpm validate`'s figure, compilation included
while the variant is not in the cache), as wall / estimate. Then four of the examples start
at once in one cache where each ran before (every process should compile nothing), and `mpm serve` starts on
a warm cache: seconds to `/readyz` 200, from a job's submission to its first step, and from
a kill -9 of the worker running it to the job stepping again (a job's lease, MPM_LEASE_SECONDS,
then a live worker's sweep). Figures are wall times on whatever else the machine
is doing: run it on a quiet machine, and twice.
"""
from __future__ import annotations

import argparse
import json
import os
import signal
import socket
import subprocess
import sys
import tempfile
import time
import urllib.request
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from solver.examples import list_examples, load_example  # noqa: E402

DEFAULT = ["two_disks", "mms_segment_1d", "sod_shock_tube", "heated_plate_2d", "column_under_gravity_2d",
           "polygon_2d", "elastic_cube_3d"]


def _start(name: str, cache: Path, out: Path) -> tuple[subprocess.Popen, float]:
    scene = out / f"{name}.json"
    scene.parent.mkdir(parents=True, exist_ok=True)
    scene.write_text(json.dumps(load_example(name)))
    env = dict(os.environ, MPM_CACHE_DIR=str(cache))
    command = [sys.executable, "-m", "solver", "run", str(scene), "-o", str(out / name), "--progress", "json"]
    return subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=env), time.perf_counter()


def _follow(process: subprocess.Popen, launched: float) -> dict:
    """Read a run's progress lines as they come: its first step's time, its estimate, its done line."""
    first_step = estimate = None
    done = {}
    for line in process.stdout:
        if not line.startswith("{"):
            continue
        item, now = json.loads(line), time.perf_counter() - launched
        if item.get("event") == "done":
            done = item
        elif estimate is None and item.get("eta_seconds") is not None and item.get("stage") == "compiling":
            estimate = now + item["eta_seconds"]
        if first_step is None and item.get("stage") == "stepping":
            first_step = now
    wall = time.perf_counter() - launched
    if process.wait() != 0 or not done:
        raise RuntimeError(process.stderr.read()[-2000:])
    return {"first_step_s": first_step, "wall_s": wall, "compiled": done["compiled"],
            "compile_s": done["compile_seconds"], "estimate_s": estimate,
            "wall_over_estimate": wall / estimate if estimate else None}


def cold_first_step(name: str, cache: Path, out: Path) -> float:
    """Seconds from launch to the first step of the example's own file (its mesh files beside it)
    in an empty cache; the run and its precompile helper are stopped there (one process group)."""
    env = dict(os.environ, MPM_CACHE_DIR=str(cache))
    command = [sys.executable, "-m", "solver", "run", str(ROOT / "examples" / f"{name}.json"), "-o", str(out / name),
               "--progress", "json"]
    process = subprocess.Popen(command, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                               env=env, start_new_session=True)
    launched = time.perf_counter()
    try:
        for line in process.stdout:
            if line.startswith("{") and json.loads(line).get("stage") == "stepping":
                return time.perf_counter() - launched
        raise RuntimeError(f"{name}: ended (exit {process.wait()}) before its first step")
    finally:
        os.killpg(process.pid, signal.SIGKILL)
        process.wait()


def first_steps(names: list[str], tmp: Path) -> list[dict]:
    rows = []
    for name in names:
        seconds = cold_first_step(name, tmp / f"cache-{name}", tmp / "first")
        rows.append({"example": name, "cold_first_step_s": seconds})
        print(f"{name:28s} cold: first step {seconds:6.1f} s", flush=True)
    return rows


def run(name: str, cache: Path, out: Path) -> dict:
    return _follow(*_start(name, cache, out))


def together(names: list[str], cache: Path, out: Path) -> list[dict]:
    """Each example run once in `cache` (one after another), then all of them at once in it,
    each process's lines read by a thread of its own (so each first step is timed as it comes)."""
    for name in names:
        run(name, cache, out / "priming")
    started = [_start(name, cache, out / "together") for name in names]
    with ThreadPoolExecutor(len(started)) as pool:
        runs = list(pool.map(lambda pair: _follow(*pair), started))
    return [{"example": name, **result} for name, result in zip(names, runs)]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _get(url: str) -> dict | None:
    try:
        with urllib.request.urlopen(url, timeout=5) as answer:
            return json.loads(answer.read()) if answer.status == 200 else None
    except (OSError, ValueError):
        return None


def _wait(condition, timeout: float, what: str):
    deadline = time.perf_counter() + timeout
    while time.perf_counter() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(0.1)
    raise RuntimeError(f"{what}: not in {timeout:.0f} s")


def _worker_pids(serve_pid: int) -> list[int]:
    """`mpm serve`'s worker: its child running `-m worker` (Linux /proc)."""
    found = []
    for entry in Path("/proc").iterdir():
        try:
            if entry.name.isdigit() and int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1]) == serve_pid \
                    and b"worker" in (entry / "cmdline").read_bytes():
                found.append(int(entry.name))
        except OSError:
            continue
    return found


def serve(cache: Path, data: Path, scene: dict) -> dict:
    """`mpm serve` on the given kernel cache: seconds to `/readyz` 200, from a job's submission
    to its first step, and from a kill -9 of the worker running it to the job stepping again."""
    port = _free_port()
    base = f"http://127.0.0.1:{port}"
    env = dict(os.environ, MPM_CACHE_DIR=str(cache), MPM_DATA_DIR=str(data), MPM_PORT=str(port))
    env.pop("MPM_REDIS_URL", None)
    launched = time.perf_counter()
    process = subprocess.Popen([str(Path(sys.executable).with_name("mpm")), "serve", "--port", str(port)], cwd=ROOT,
                               env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        _wait(lambda: _get(f"{base}/readyz"), 300, "/readyz")
        ready = time.perf_counter() - launched
        request = urllib.request.Request(f"{base}/v1/jobs", data=json.dumps({"scene": scene}).encode(),
                                         headers={"content-type": "application/json"})
        submitted = time.perf_counter()
        with urllib.request.urlopen(request, timeout=30) as answer:
            job = json.loads(answer.read())["id"]
        record = f"{base}/v1/jobs/{job}"
        _wait(lambda: (_get(record) or {}).get("step", 0) > 0, 600, "the job's first step")
        first_step = time.perf_counter() - submitted
        for pid in _worker_pids(process.pid):
            os.kill(pid, signal.SIGKILL)
        killed = time.perf_counter()
        _wait(lambda: (_get(record) or {}).get("attempts", 1) > 1 and (_get(record) or {}).get("step", 0) > 0,
              600, "the job stepping again")
        return {"ready_s": ready, "job_first_step_s": first_step, "resumed_s": time.perf_counter() - killed}
    finally:
        process.terminate()
        process.wait(120)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--examples", nargs="+", default=DEFAULT)
    parser.add_argument("--all", action="store_true", help="every example")
    parser.add_argument("--json", type=Path, help="write the figures here")
    parser.add_argument("--no-cold", action="store_true", help="only the processes at once and mpm serve")
    parser.add_argument("--first-steps", action="store_true",
                        help="only each example's cold first step (stopped there; with --all: every example)")
    args = parser.parse_args()
    names = [e["name"] for e in list_examples()] if args.all else args.examples
    if args.first_steps:
        with tempfile.TemporaryDirectory(prefix="mpm-startup-") as tmp:
            rows = first_steps(names, Path(tmp))
        if args.json:
            args.json.write_text(json.dumps(rows, indent=1))
        return 0
    rows = []
    with tempfile.TemporaryDirectory(prefix="mpm-startup-") as tmp:
        tmp = Path(tmp)
        for name in [] if args.no_cold else names:
            cache = tmp / f"cache-{name}"
            cold, warm = run(name, cache, tmp / "cold"), run(name, cache, tmp / "warm")
            rows.append({"example": name, "cold": cold, "warm": warm})
            print(f"{name:28s} cold: first step {cold['first_step_s']:6.1f} s, {cold['compiled']:3d} compiled "
                  f"({cold['compile_s']:.1f} s), wall/estimate {cold['wall_over_estimate'] or 0:.2f} | warm: first "
                  f"step {warm['first_step_s']:5.2f} s, {warm['compiled']} compiled, wall/estimate "
                  f"{warm['wall_over_estimate'] or 0:.2f}", flush=True)
        shared = tmp / "shared-cache"
        four = together(names[:4], shared, tmp)
        print("four at once, warm:", ", ".join(f"{r['example']} {r['compiled']} compiled, first step "
                                               f"{r['first_step_s']:.2f} s" for r in four), flush=True)
        long_job = load_example(names[0])
        long_job["time"] = {**long_job["time"], "end": 1000 * long_job["time"]["end"]}   # still running when killed
        service = serve(shared, tmp / "data", long_job)
        print(f"mpm serve on a warm cache: /readyz 200 after {service['ready_s']:.1f} s, a job's first step "
              f"{service['job_first_step_s']:.1f} s after its submission, stepping again "
              f"{service['resumed_s']:.1f} s after a kill -9 of its worker", flush=True)
    if args.json:
        args.json.write_text(json.dumps({"examples": rows, "together": four, "serve": service}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
