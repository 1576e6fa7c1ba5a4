"""The settings every process of the service reads, from the environment (`MPM_*`):
where the job records and the results are, how the workers run jobs and keep them,
the logs. The API's own settings (where it listens, what it admits, who may call it)
are service.settings.ApiSettings, built on these.
"""
from __future__ import annotations

import os
import sys
from functools import lru_cache
from pathlib import Path
from typing import Literal

from pydantic import Field
from pydantic_settings import BaseSettings, SettingsConfigDict


def default_data_dir() -> Path:
    """The platform's per-user data folder, with an `mpm` folder in it."""
    home = Path.home()
    if sys.platform == "win32":
        base = Path(os.environ.get("LOCALAPPDATA") or home / "AppData" / "Local")
    elif sys.platform == "darwin":
        base = home / "Library" / "Application Support"
    else:
        base = Path(os.environ.get("XDG_DATA_HOME") or home / ".local" / "share")
    return base / "mpm"


class Settings(BaseSettings):
    """The API's and the workers' settings, each from the environment variable `MPM_<NAME>`."""

    model_config = SettingsConfigDict(env_prefix="MPM_", extra="ignore")

    redis_url: str | None = Field(
        None, description="Redis for the queue and the job records; unset: `mpm serve` embeds one")
    data_dir: Path = Field(default_factory=default_data_dir,
                           description="results (one folder per job) and the embedded Redis' data")

    # Workers.
    worker_concurrency: int = Field(1, gt=0, description="jobs one `mpm worker` runs at once")
    max_job_seconds: float = Field(24 * 3600.0, gt=0, description="wall-clock limit of one job")
    progress_interval: float = Field(0.5, gt=0, description="seconds between job-record updates")
    cancel_grace_seconds: float = Field(10.0, gt=0, description="SIGTERM to SIGKILL on cancel")
    warmup: bool = Field(True, description="compile the solver kernels when a worker starts")
    lease_seconds: float = Field(30.0, gt=0, description="a running job whose worker is silent this "
                                                          "long is put back on the queue")

    # Where a job's solver runs (worker/launcher.py): "local", a child process of the worker;
    # "slurm", a Slurm batch job (worker/slurm.py; docs/service.md, "Running jobs on a Slurm cluster").
    launcher: Literal["local", "slurm"] = Field("local", description="local: a child process of the worker; "
                                                                      "slurm: a Slurm batch job (sbatch)")
    slurm_partition: str | None = Field(None, description="sbatch --partition (unset: the cluster's default)")
    slurm_account: str | None = Field(None, description="sbatch --account (unset: the user's default)")
    slurm_time_limit: str | None = Field(None, description="sbatch --time, e.g. 2:00:00 (unset: the "
                                                           "partition's); a job ended by it resumes")

    # Nothing lost: checkpoints, attempts, disk (docs/reliability.md).
    checkpoint_seconds: float = Field(60.0, gt=0, description="wall-clock seconds between a job's "
                                                               "restart checkpoints")
    max_attempts: int = Field(3, ge=1, description="starts of a job whose run was lost (worker or "
                                                    "solver killed) before it is failed")
    max_job_bytes: int = Field(20 * 2**30, gt=0, description="size limit of one job's folder")
    max_total_bytes: int = Field(500 * 2**30, gt=0, description="size limit of all jobs' folders")
    retention_days: float = Field(30.0, ge=0, description="finished jobs older than this are deleted "
                                                           "with their files (0: kept for ever)")
    min_free_bytes: int = Field(2**30, ge=0, description="a job is not admitted while the data folder's "
                                                         "file system has less free space than this")

    # Webhooks (worker/webhooks.py): a job's or a sweep's final record POSTed to its callback_url.
    webhook_secret: str | None = Field(None, description="key of the X-MPM-Signature HMAC-SHA256; "
                                                         "unset: callback_url is refused")
    webhook_allow: str = Field("127.0.0.0/8:1024-65535,[::1]:1024-65535,localhost:1024-65535",
                               description="comma-separated networks (CIDR) and host names a "
                                           "callback_url may point to, each with an optional :PORT or "
                                           ":FIRST-LAST; default: loopback, unprivileged ports only (the "
                                           "service's own Redis port is refused whatever this says)")

    log_level: str = "INFO"

    @property
    def jobs_dir(self) -> Path:
        return self.data_dir / "jobs"

    @property
    def visibility_timeout(self) -> int:
        """Seconds before Redis hands an unacknowledged job to another worker:
        longer than the longest job, so that only a lost worker's job is redelivered."""
        return int(self.max_job_seconds + 3600)


@lru_cache
def get_settings() -> Settings:
    return Settings()
