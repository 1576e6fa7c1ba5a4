"""What the fault tests share: the environment of a fault-tolerant service with short
leases and frequent checkpoints, and `mpm serve` started on its own data folder."""
from __future__ import annotations

import os
from pathlib import Path

from service_support import MPM, Process, answers, free_port, wait_until

FAULT_ENV = {
    "MPM_LEASE_SECONDS": "5",          # a lost worker's job is requeued within seconds
    "MPM_CHECKPOINT_SECONDS": "0.5",   # a checkpoint every half second of a job
    "MPM_PROGRESS_INTERVAL": "0.2",
    "MPM_CANCEL_GRACE_SECONDS": "5",
    "MPM_MAX_ATTEMPTS": "3",
    "MPM_MAX_JOB_BYTES": str(4 * 2**20),  # the big-output test goes over it, the others stay far under
    "MPM_WARMUP": "false",             # the kernels are in numba's on-disk cache already
    "PYTHONUNBUFFERED": "1",
}


def fault_env(data_dir: Path) -> dict[str, str]:
    """The environment without the caller's MPM_* settings, with FAULT_ENV; but MPM_FMA, which
    the kernels are compiled with (tests/conftest.py): the tests compare the service's results
    with a run of this process bit for bit."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("MPM_") or k == "MPM_FMA"}
    return {**env, **FAULT_ENV, "MPM_DATA_DIR": str(data_dir)}


class Serve:
    """`mpm serve` on a free port with its own data folder."""

    def __init__(self, data_dir: Path, log_dir: Path):
        self.data_dir, self.log_dir = data_dir, log_dir
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.env = fault_env(data_dir)
        self.process = Process("serve", [*MPM, "serve", "--port", str(self.port)], self.env, log_dir)

    def start(self) -> "Serve":
        self.process.start()
        wait_until(answers(self.url, "/readyz"), 300, "mpm serve ready", processes=(self.process,))
        return self

    def children(self) -> dict[str, int]:
        """The pids of the serve's worker and embedded Redis."""
        found = {}
        for entry in Path("/proc").iterdir():
            if not entry.name.isdigit():
                continue
            try:
                stat = (entry / "stat").read_text()
                cmdline = (entry / "cmdline").read_bytes().decode(errors="ignore")
            except OSError:
                continue
            fields = stat.rsplit(")", 1)[1].split()
            if int(fields[1]) == self.process.popen.pid and fields[0] != "Z":
                found["redis" if "redis" in cmdline else "worker"] = int(entry.name)
        return found

    def job_dir(self, job_id: str) -> Path:
        return self.data_dir / "jobs" / job_id
