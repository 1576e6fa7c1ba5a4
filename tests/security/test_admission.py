"""Admission without tokens and on a full disk (issue 21): the anonymous caller has the
MPM_QUOTA_* quotas as any owner, a sweep is admitted whole or not at all, and a job
is refused with 507 and the figures when the disk budget is spent, before anything
is stored."""
from __future__ import annotations

import os

import pytest

from quota_api import QuotaApi
from service_support import two_disks

SMALL = two_disks("small", end=0.01)


def _jobs_on_disk(api: QuotaApi) -> int:
    jobs = api.data_dir / "jobs"
    return len(os.listdir(jobs)) if jobs.exists() else 0


@pytest.fixture(scope="module")
def anonymous_api(tmp_path_factory):
    api = QuotaApi(tmp_path_factory.mktemp("anonymous-api"),
                   {"MPM_QUOTA_QUEUED_JOBS": "3", "MPM_QUOTA_ACTIVE_JOBS": "5"}, tokens=False)
    yield api
    api.stop()


def test_the_anonymous_caller_has_the_quotas_too(anonymous_api):
    with anonymous_api.client(None) as client:
        sweep = {"scene": SMALL, "parameters": {"/time/end": [0.01, 0.02]}}
        assert client.post("/v1/sweeps", json=sweep).status_code == 202          # 2 queued
        over = client.post("/v1/sweeps", json=sweep)                            # 4 > 3
        assert over.status_code == 429, over.text
        assert over.json()["error"]["details"]["limit"] == "MPM_QUOTA_QUEUED_JOBS"
        assert "2 jobs asked for" in over.json()["error"]["message"]
        assert client.post("/v1/jobs", json={"scene": SMALL}).status_code == 202  # 3 queued
        refused = client.post("/v1/jobs", json={"scene": SMALL})
        assert refused.status_code == 429 and int(refused.headers["retry-after"]) > 0
        assert refused.json()["error"]["details"]["limit"] == "MPM_QUOTA_QUEUED_JOBS"
        assert len(client.get("/v1/jobs").json()["jobs"]) == 3 == _jobs_on_disk(anonymous_api)
        assert len(client.get("/v1/sweeps").json()["sweeps"]) == 1  # the refused sweep left no trace


@pytest.mark.parametrize("setting,value,limit", [
    ("MPM_MIN_FREE_BYTES", str(2**62), "MPM_MIN_FREE_BYTES"),   # more than any disk has free
    ("MPM_MAX_TOTAL_BYTES", "1000", "MPM_MAX_TOTAL_BYTES"),     # the results already take 4000 bytes
])
def test_a_full_disk_refuses_jobs_at_submission(tmp_path, setting, value, limit):
    api = QuotaApi(tmp_path, {setting: value}, tokens=False)
    try:
        old = api.data_dir / "jobs" / "0b7d5e1c-2a8e-4a55-9d0f-7c1f3b8f6e21"
        old.mkdir(parents=True)
        (old / "result.h5").write_bytes(b"x" * 4000)
        with api.client(None) as client:
            for path, body in (("/v1/jobs", {"scene": SMALL}),
                               ("/v1/sweeps", {"scene": SMALL, "parameters": {"/time/end": [0.01]}})):
                answer = client.post(path, json=body)
                assert answer.status_code == 507, answer.text
                error = answer.json()["error"]
                assert error["code"] == "insufficient_storage" and error["details"]["limit"] == limit
                assert error["details"]["used_bytes"] == 4000 and error["details"]["free_bytes"] > 0
                assert limit in error["message"]
            assert client.get("/v1/jobs").json()["jobs"] == [] and _jobs_on_disk(api) == 1
            assert client.post("/v1/scenes/validate", json=SMALL).status_code == 200  # validating costs no disk
    finally:
        api.stop()
