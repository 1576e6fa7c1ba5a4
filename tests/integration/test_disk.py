"""The disk of the jobs: retention (finished jobs past the period are removed with their
files, nothing else is) and the size limits a running job is checked against."""
from __future__ import annotations

from datetime import datetime, timedelta, timezone

from core.paths import JobFiles, new_job_id
from worker.disk import DiskQuota, folder_bytes, remove_expired


def iso(days_ago: float) -> str:
    when = datetime.now(timezone.utc) - timedelta(days=days_ago)
    return when.isoformat(timespec="milliseconds").replace("+00:00", "Z")


def make_job(store, jobs_dir, status: str, finished_days_ago: float | None) -> str:
    job_id = new_job_id()
    store.create(job_id, {"name": status}, max_active=1000)
    if status != "queued":
        store.transition(job_id, ["queued"], status,
                         finished_at=iso(finished_days_ago) if finished_days_ago is not None else None)
    folder = JobFiles(jobs_dir, job_id).dir
    folder.mkdir(parents=True)
    (folder / "result.h5").write_bytes(b"x" * 100)
    return job_id


def test_retention_removes_finished_jobs_past_the_period_and_nothing_else(store, tmp_path):
    old = {status: make_job(store, tmp_path, status, 10.0) for status in ("succeeded", "failed", "cancelled")}
    recent = make_job(store, tmp_path, "succeeded", 1.0)
    running = make_job(store, tmp_path, "running", None)
    queued = make_job(store, tmp_path, "queued", None)

    removed = remove_expired(store, tmp_path, retention_days=7)
    assert sorted(removed) == sorted(old.values())
    for job_id in old.values():
        assert store.get(job_id) is None and not JobFiles(tmp_path, job_id).dir.exists()
    for job_id in (recent, running, queued):
        assert store.get(job_id) is not None and JobFiles(tmp_path, job_id).dir.exists()
    assert remove_expired(store, tmp_path, retention_days=0) == []  # 0: kept for ever
    assert store.get(recent) is not None


def test_quota_names_the_limit_a_job_went_over(tmp_path):
    mine, other = tmp_path / "a", tmp_path / "b"
    mine.mkdir()
    (mine / "previews").mkdir()
    other.mkdir()
    (mine / "result.h5").write_bytes(b"x" * 600)
    (mine / "previews" / "p.png").write_bytes(b"x" * 100)
    (other / "result.h5").write_bytes(b"x" * 500)
    assert folder_bytes(mine) == 700 and folder_bytes(tmp_path) == 1200

    assert DiskQuota(tmp_path, mine, max_job_bytes=700, max_total_bytes=1200).check() is None
    over_job = DiskQuota(tmp_path, mine, max_job_bytes=699, max_total_bytes=10**9)
    assert "MPM_MAX_JOB_BYTES" in over_job.check() and over_job.reason.startswith("the job's results reached 700 B")
    over_total = DiskQuota(tmp_path, mine, max_job_bytes=10**9, max_total_bytes=1199)
    assert "MPM_MAX_TOTAL_BYTES" in over_total.check()
