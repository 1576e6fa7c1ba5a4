"""Per-owner quotas on a live API (tokens on, no worker: jobs stay queued unless a
test moves them): queued jobs, queued + running jobs, particle-steps a day. Each
refusal is a 429 naming the setting, with a Retry-After, and leaves no trace."""
from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

import pytest

from quota_api import QuotaApi
from service_support import two_disks

from solver.scene_checks import load_scene
from solver.summary import summarize


def cost(scene: dict) -> float:
    """Particle-steps the service charges: particles x estimated steps, as service/quotas.py."""
    summary = summarize(load_scene(scene))
    return float(summary.particles * summary.estimated_steps)


SMALL = two_disks("small", end=0.01)   # 10 steps
LARGE = two_disks("large", end=1.0)    # 1000 steps: 100 times SMALL
DAILY = 2.5 * cost(LARGE)              # two LARGE and a few SMALL fit in a day, not three LARGE


@pytest.fixture(scope="module")
def quota_api(tmp_path_factory):
    api = QuotaApi(tmp_path_factory.mktemp("quota-api"), {
        "MPM_QUOTA_QUEUED_JOBS": "2", "MPM_QUOTA_ACTIVE_JOBS": "3",
        "MPM_QUOTA_PARTICLE_STEPS_PER_DAY": repr(DAILY)})
    yield api
    api.stop()


def _jobs_on_disk(api: QuotaApi) -> int:
    jobs = api.data_dir / "jobs"
    return len(os.listdir(jobs)) if jobs.exists() else 0


def _refused(answer, limit: str) -> dict:
    assert answer.status_code == 429, answer.text
    error = answer.json()["error"]
    assert error["code"] == "too_many_jobs" and error["details"]["limit"] == limit
    assert int(answer.headers["retry-after"]) > 0
    return error


def test_queued_and_active_quotas(quota_api):
    with quota_api.client("alice") as alice, quota_api.client("bob") as bob:
        accepted = [alice.post("/v1/jobs", json={"scene": SMALL}) for _ in range(2)]
        assert [a.status_code for a in accepted] == [202, 202], accepted[-1].text
        first, second = (a.json()["id"] for a in accepted)
        on_disk = _jobs_on_disk(quota_api)
        _refused(alice.post("/v1/jobs", json={"scene": SMALL}), "MPM_QUOTA_QUEUED_JOBS")
        assert _jobs_on_disk(quota_api) == on_disk
        assert len(alice.get("/v1/jobs").json()["jobs"]) == 2
        # quotas are per owner: bob is not held back by alice's jobs
        assert bob.post("/v1/jobs", json={"scene": SMALL}).status_code == 202

        # a worker took the first: one running, one queued, room for one more in the queue
        quota_api.store.transition(first, ["queued"], "running")
        assert alice.post("/v1/jobs", json={"scene": SMALL}).status_code == 202
        # two running, one queued: the queue has room but three jobs are active
        quota_api.store.transition(second, ["queued"], "running")
        error = _refused(alice.post("/v1/jobs", json={"scene": SMALL}), "MPM_QUOTA_ACTIVE_JOBS")
        assert error["details"]["max"] == 3
        # a finished job no longer counts
        quota_api.store.transition(first, ["running"], "succeeded")
        assert alice.post("/v1/jobs", json={"scene": SMALL}).status_code == 202


def test_a_burst_cannot_overrun_the_queue_quota(quota_api):
    """Eight submissions at once: the check and the creation are one step, so exactly two get in."""
    with quota_api.client("fuzz") as caller:
        with ThreadPoolExecutor(8) as pool:
            codes = sorted(pool.map(lambda _: caller.post("/v1/jobs", json={"scene": SMALL}).status_code,
                                    range(8)))
        assert codes == [202, 202] + [429] * 6
        assert len(caller.get("/v1/jobs").json()["jobs"]) == 2


def test_particle_steps_per_day(quota_api):
    with quota_api.client("bob") as bob:
        # bob has one SMALL job (1/100 of LARGE) from the first test at most; cancel frees the queue
        for job in bob.get("/v1/jobs", params={"status": "queued"}).json()["jobs"]:
            bob.post(f"/v1/jobs/{job['id']}/cancel")
        ids = []
        for _ in range(2):
            answer = bob.post("/v1/jobs", json={"scene": LARGE})
            assert answer.status_code == 202, answer.text
            ids.append(answer.json()["id"])
            bob.post(f"/v1/jobs/{ids[-1]}/cancel")  # the charge stays: it is made at submission
        error = _refused(bob.post("/v1/jobs", json={"scene": LARGE}), "MPM_QUOTA_PARTICLE_STEPS_PER_DAY")
        assert "00:00 UTC" in error["message"]
        retry = int(bob.post("/v1/jobs", json={"scene": LARGE}).headers["retry-after"])
        assert 0 < retry <= 86400 + 1  # until the next UTC midnight


def test_a_job_bigger_than_a_whole_day_is_invalid_not_throttled(quota_api):
    huge = two_disks("huge", end=3.0)  # 3000 steps: 1.2 days of quota
    with quota_api.client("alice") as alice:
        answer = alice.post("/v1/jobs", json={"scene": huge})
    assert answer.status_code == 422
    [detail] = answer.json()["error"]["details"]
    assert detail["path"] == "scene" and detail["limit"] == "MPM_QUOTA_PARTICLE_STEPS_PER_DAY"
