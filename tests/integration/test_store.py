"""The job store against a real (embedded) Redis: atomic transitions, quota, paging, leases."""
from __future__ import annotations

import time

import pytest

from core.paths import new_job_id
from core.store import CursorError


def _create(store, n=1, max_active=100, **fields):
    ids = []
    for _ in range(n):
        job_id = new_job_id()
        assert store.create(job_id, {"name": "t", **fields}, max_active)
        ids.append(job_id)
    return ids


def test_create_and_read_back_types(store):
    [job_id] = _create(store, summary={"particles": 4}, energies={"kinetic": 0.5}, error=None)
    job = store.get(job_id)
    assert job["status"] == "queued" and job["id"] == job_id
    assert job["summary"] == {"particles": 4} and job["energies"] == {"kinetic": 0.5}
    assert job["error"] is None
    assert store.get(new_job_id()) is None


def test_transitions_only_from_allowed_status(store):
    [job_id] = _create(store)
    assert store.transition(job_id, ["queued"], "running", step=1) == "queued"
    assert store.get(job_id)["status"] == "running"
    # not allowed: the status stays and no field is written
    assert store.transition(job_id, ["queued"], "failed", step=99) == "running"
    assert store.get(job_id)["step"] == 1
    assert store.update_running(job_id, step=5)
    assert store.transition(job_id, ["running"], "succeeded") == "running"
    assert not store.update_running(job_id, step=6)
    assert store.get(job_id)["step"] == 5
    assert store.transition(new_job_id(), ["queued"], "running") is None


def test_status_indexes_follow_transitions(store):
    a, b = _create(store, 2)
    store.transition(a, ["queued"], "running")
    assert [j["id"] for j in store.list("running").jobs] == [a]
    assert [j["id"] for j in store.list("queued").jobs] == [b]
    assert store.count_active() == 2
    store.transition(a, ["running"], "failed")
    assert store.count_active() == 1
    assert [j["id"] for j in store.list("failed").jobs] == [a]


def test_quota_counts_queued_and_running(store):
    a, b = _create(store, 2, max_active=2)
    assert not store.create(new_job_id(), {"name": "over"}, 2)
    assert store.redis.zcard("mpm:jobs") == 2  # the refused job left no trace
    store.transition(a, ["queued"], "succeeded")
    assert store.create(new_job_id(), {"name": "fits"}, 2)


def test_cancel_queued_at_once_running_by_flag(store):
    queued, running, done = _create(store, 3)
    store.transition(running, ["queued"], "running")
    store.transition(done, ["queued"], "succeeded")
    assert store.request_cancel(queued) == "queued"
    assert store.get(queued)["status"] == "cancelled" and store.get(queued)["finished_at"]
    assert store.request_cancel(running) == "running"
    assert store.get(running)["status"] == "running" and store.cancel_requested(running)
    assert store.request_cancel(done) == "succeeded"
    assert not store.cancel_requested(done)


def test_delete_only_finished(store):
    running, done = _create(store, 2)
    store.transition(running, ["queued"], "running")
    store.transition(done, ["queued"], "cancelled")
    assert store.delete(running) == "running" and store.get(running)
    assert store.delete(done) == "cancelled"
    assert store.get(done) is None
    assert done not in store.redis.zrange("mpm:jobs", 0, -1)
    assert done not in store.redis.zrange("mpm:jobs:cancelled", 0, -1)


def test_paging_newest_first_without_gaps_or_repeats(store):
    ids = _create(store, 7)
    # two jobs with the same creation score: paging must still be exact
    twin = new_job_id()
    store.create(twin, {"name": "twin"}, 100)
    store.redis.zadd("mpm:jobs", {twin: store.redis.zscore("mpm:jobs", ids[3])})
    seen, cursor = [], None
    while True:
        page = store.list(limit=3, cursor=cursor)
        seen += [j["id"] for j in page.jobs]
        cursor = page.next_cursor
        if cursor is None:
            break
    assert sorted(seen) == sorted(ids + [twin]) and len(seen) == len(set(seen))
    assert seen.index(ids[6]) < seen.index(ids[5]) < seen.index(ids[0])
    with pytest.raises(CursorError):
        store.list(cursor="not-a-cursor")


def test_lease_is_exclusive_and_expires(store):
    job_id = new_job_id()
    assert store.acquire_lease(job_id, "a", 0.3)
    assert not store.acquire_lease(job_id, "b", 0.3)
    assert store.renew_lease(job_id, "a", 0.3) and not store.renew_lease(job_id, "b", 0.3)
    store.release_lease(job_id, "b")  # not the holder: nothing happens
    assert not store.acquire_lease(job_id, "b", 0.3)
    time.sleep(0.4)
    assert store.acquire_lease(job_id, "b", 0.3)


def test_workers_heartbeat(store):
    store.heartbeat("w1")
    assert store.live_workers(5) == ["w1"]
    store.worker_gone("w1")
    assert store.live_workers(5) == []


def test_warming_workers_are_the_live_ones_that_said_so(store):
    store.heartbeat("w1")
    store.heartbeat("w2")
    store.set_warming("w1", True)
    store.set_warming("gone", True)   # a worker killed while warming up: not live, not listed
    assert store.warming_workers() == ["w1"]
    store.set_warming("w1", False)
    assert store.warming_workers() == []
    store.set_warming("w2", True)
    store.worker_gone("w2")
    assert store.warming_workers() == []


def test_running_jobs_without_lease_are_requeued(store):
    alive, lost = _create(store, 2)
    for job_id in (alive, lost):
        store.transition(job_id, ["queued"], "running", progress=0.5)
    store.acquire_lease(alive, "w1", 30)
    assert store.requeue_orphans() == [lost]
    assert store.get(lost)["status"] == "queued" and store.get(lost)["progress"] == 0.0
    assert store.get(lost)["stage"] == "queued"
    assert store.get(alive)["status"] == "running"
    assert [j["id"] for j in store.list("queued").jobs] == [lost]
    assert store.requeue_orphans() == []


def test_the_embedded_redis_writes_every_write_to_disk_before_answering(redis_server):
    """appendfsync always: with everysec Redis may answer before it writes the append-only file
    (while a background fsync runs), and a kill -9 then loses acknowledged writes
    (docs/reliability.md, Redis)."""
    import redis
    client = redis.Redis.from_url(redis_server.url, decode_responses=True)
    try:
        assert client.config_get("appendonly") == {"appendonly": "yes"}
        assert client.config_get("appendfsync") == {"appendfsync": "always"}
    finally:
        client.close()
