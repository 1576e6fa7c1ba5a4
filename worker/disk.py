"""The disk the jobs' folders use: a size limit per job and for all jobs together
(checked while a job runs), and the removal of finished jobs older than the
retention period (a periodic chore of every worker, see worker/heartbeat.py)."""
from __future__ import annotations

import json
import logging
import shutil
import time
from datetime import datetime
from pathlib import Path

from core.disk import folder_bytes, human
from core.paths import JobFiles
from core.models import FINISHED
from core.store import JobStore, job_key, status_index

log = logging.getLogger("mpm.worker")

# The total of the other jobs' folders is measured again at most this often (a walk of
# every folder); the job's own folder is measured at each check (a few files).
TOTAL_EVERY_SECONDS = 30.0

__all__ = ["DiskQuota", "folder_bytes", "human", "remove_expired"]


class DiskQuota:
    """`check()` names the limit a job's folder went over, or None."""

    def __init__(self, jobs_dir: Path, job_dir: Path, max_job_bytes: int, max_total_bytes: int):
        self.jobs_dir, self.job_dir = Path(jobs_dir), Path(job_dir)
        self.max_job, self.max_total = max_job_bytes, max_total_bytes
        self._others = 0
        self._measured_at = -float("inf")
        self.reason: str | None = None  # the last limit found exceeded

    def check(self) -> str | None:
        mine = folder_bytes(self.job_dir)
        if time.monotonic() - self._measured_at > TOTAL_EVERY_SECONDS:
            self._others = folder_bytes(self.jobs_dir) - mine
            self._measured_at = time.monotonic()
        if mine > self.max_job:
            self.reason = (f"the job's results reached {human(mine)}, over the limit of "
                           f"{human(self.max_job)} per job (MPM_MAX_JOB_BYTES)")
        elif self._others + mine > self.max_total:
            self.reason = (f"the results of all jobs reached {human(self._others + mine)}, over the "
                           f"limit of {human(self.max_total)} (MPM_MAX_TOTAL_BYTES)")
        else:
            return None
        return self.reason


def _timestamp(iso: str | None) -> float | None:
    return datetime.fromisoformat(iso.replace("Z", "+00:00")).timestamp() if iso else None


def remove_expired(store: JobStore, jobs_dir: Path, retention_days: float) -> list[str]:
    """Delete the finished jobs (records and folders) that finished more than
    `retention_days` ago; returns their ids. 0 days: keep everything."""
    if retention_days <= 0:
        return []
    cutoff = time.time() - retention_days * 86400.0
    removed = []
    for status in FINISHED:
        ids = store.redis.zrange(status_index(status), 0, -1)
        pipe = store.redis.pipeline(transaction=False)
        for job_id in ids:
            pipe.hget(job_key(job_id), "finished_at")
        for job_id, raw in zip(ids, pipe.execute()):
            finished = _timestamp(json.loads(raw)) if raw else None
            if finished is None or finished > cutoff or store.delete(job_id) not in FINISHED:
                continue
            shutil.rmtree(JobFiles(jobs_dir, job_id).dir, ignore_errors=True)
            removed.append(job_id)
            log.info("job removed: past the retention period", extra={"job_id": job_id})
    return removed
