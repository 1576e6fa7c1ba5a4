"""`mpm serve` on its own, as a user starts it: embedded Redis + a worker + the API in
one command, stopped by Ctrl-C; its data survives a restart, and a job that was
running when it stopped runs again."""
from __future__ import annotations

import os
import signal
from pathlib import Path

import httpx

from service_support import (MPM, Process, answers, boxed, free_port, long_running, processes_with,
                             wait_for_status, wait_until)


def _children(pid: int) -> list[int]:
    """The processes whose parent is `pid` (Linux /proc)."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                found.append(int(entry.name))
    return found


def _gone(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return True
    return (Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]) == "Z"


def _serve(tmp_path: Path, port: int) -> Process:
    env = {k: v for k, v in os.environ.items() if not k.startswith("MPM_")}
    env.update(MPM_DATA_DIR=str(tmp_path / "data"), PYTHONUNBUFFERED="1")
    command = [*MPM, "serve", "--port", str(port)]
    return Process("serve", command, env, tmp_path).start()


def test_mpm_serve_runs_everything_and_ctrl_c_stops_it(tmp_path):
    port = free_port()
    url = f"http://127.0.0.1:{port}"
    serve = _serve(tmp_path, port)
    try:
        wait_until(answers(url, "/readyz"), 300, "mpm serve ready", processes=(serve,))
        children = _children(serve.popen.pid)
        assert len(children) == 2  # the embedded Redis and the worker
        assert (tmp_path / "data" / "redis" / "appendonly.aof").exists()

        with httpx.Client(base_url=url, timeout=30) as api:
            quick = api.post("/v1/jobs", json={"scene": boxed("quick", end=2.0)}).json()
            # ready before its warm-up: on an empty kernel cache the first job compiles beside it
            assert wait_for_status(api, quick["id"], timeout=400)["status"] == "succeeded"
            interrupted = api.post("/v1/jobs", json={"scene": long_running("interrupted")}).json()
            wait_for_status(api, interrupted["id"], ("running",))

        serve.signal(signal.SIGINT)  # Ctrl-C
        assert serve.popen.wait(60) == 0, serve.tail()
        for pid in children:
            assert _gone(pid), f"process {pid} outlived mpm serve"
        assert not processes_with(interrupted["id"])  # its solver was stopped too

        # Started again on the same data: the jobs are still there, and the job that was
        # running when the service stopped went back to the queue and runs again.
        serve = _serve(tmp_path, port)
        wait_until(answers(url, "/readyz"), 300, "mpm serve ready again", processes=(serve,))
        with httpx.Client(base_url=url, timeout=30) as api:
            assert api.get(f"/v1/jobs/{quick['id']}").json()["status"] == "succeeded"
            again = wait_for_status(api, interrupted["id"], ("running",), timeout=60)
            assert again["attempts"] == 2
            assert api.post(f"/v1/jobs/{interrupted['id']}/cancel").status_code == 202
            assert wait_for_status(api, interrupted["id"], timeout=30)["status"] == "cancelled"
        serve.signal(signal.SIGTERM)  # as `docker stop` does: the same orderly stop
        assert serve.popen.wait(60) == 0, serve.tail()
    finally:
        serve.stop()
