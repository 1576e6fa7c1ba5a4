"""API tokens end to end, on a live service with MPM_API_TOKENS (a token file):
no /v1 call without a valid token, each caller sees, downloads, cancels and deletes
only its own jobs, another owner's job answers exactly like a missing one, and no
token reaches a log."""
from __future__ import annotations

import socket
import subprocess
import uuid

import httpx
import pytest

from secure_service import TOKENS
from service_support import MPM, long_running, two_disks, wait_for_status

from mpm_client import Client
from mpm_client.errors import NotFound, Unauthorized

V1_READS = ["/v1/jobs", "/v1/health", "/v1/examples", "/v1/examples/two_disks", "/v1/schema/scene",
            f"/v1/jobs/{uuid.uuid4()}"]
OPEN = ["/healthz", "/readyz", "/openapi.json", "/docs", "/"]


@pytest.mark.parametrize("headers", [{}, {"Authorization": "Bearer not-a-token-at-all-0000"},
                                     {"Authorization": f"Basic {TOKENS['alice']}"},
                                     {"Authorization": "Bearer"}],
                         ids=["none", "wrong", "not bearer", "empty"])
def test_every_v1_call_needs_a_valid_token(secure, headers):
    with httpx.Client(base_url=secure.url, timeout=30, headers=headers) as client:
        for path in V1_READS:
            answer = client.get(path)
            assert answer.status_code == 401, (path, answer.text)
            assert answer.json()["error"]["code"] == "unauthorized"
            assert answer.headers["www-authenticate"].startswith("Bearer")
        for path, body in (("/v1/jobs", {"scene": two_disks()}), ("/v1/scenes/validate", two_disks())):
            assert client.post(path, json=body).status_code == 401
        # refused before the body is read: an invalid body is still a 401, not a 422
        assert client.post("/v1/jobs", content=b"{not json").status_code == 401
        for path in OPEN:
            assert client.get(path).status_code == 200, path


def test_a_caller_sees_and_handles_only_its_own_jobs(alice, bob):
    job = alice.post("/v1/jobs", json={"scene": two_disks("alice's")}).json()
    assert job["owner"] == "alice"
    job_id = job["id"]
    assert wait_for_status(alice, job_id)["status"] == "succeeded"

    assert job_id in [j["id"] for j in alice.get("/v1/jobs").json()["jobs"]]
    assert job_id in [j["id"] for j in alice.get("/v1/jobs", params={"status": "succeeded"}).json()["jobs"]]
    assert job_id not in [j["id"] for j in bob.get("/v1/jobs").json()["jobs"]]
    assert all(j["owner"] == "bob" for j in bob.get("/v1/jobs").json()["jobs"])

    routes = [("GET", ""), ("GET", "/result.h5"), ("GET", "/preview.png"), ("GET", "/series"),
              ("GET", "/scene"), ("POST", "/cancel"), ("DELETE", "")]
    for method, tail in routes[:5]:
        assert alice.request(method, f"/v1/jobs/{job_id}{tail}").status_code == 200, tail
    missing = str(uuid.uuid4())
    for method, tail in routes:
        theirs = bob.request(method, f"/v1/jobs/{job_id}{tail}")
        nobodys = bob.request(method, f"/v1/jobs/{missing}{tail}")
        # 404, never 403, with the same body as an id that does not exist: ids do not leak
        assert theirs.status_code == nobodys.status_code == 404, (method, tail, theirs.text)
        assert theirs.json()["error"] == {**nobodys.json()["error"], "message": f"no job {job_id}"}

    # bob's cancel and delete changed nothing; alice's delete works
    assert alice.get(f"/v1/jobs/{job_id}").json()["status"] == "succeeded"
    assert alice.delete(f"/v1/jobs/{job_id}").status_code == 204
    assert alice.get(f"/v1/jobs/{job_id}").status_code == 404


def test_only_the_owner_cancels(alice, bob):
    job_id = alice.post("/v1/jobs", json={"scene": long_running("alice-long")}).json()["id"]
    try:
        assert bob.post(f"/v1/jobs/{job_id}/cancel").status_code == 404
        assert alice.get(f"/v1/jobs/{job_id}").json()["cancel_requested"] is False
    finally:
        assert alice.post(f"/v1/jobs/{job_id}/cancel").status_code == 202
    assert wait_for_status(alice, job_id)["status"] == "cancelled"


def test_the_sdk_takes_the_token(secure, monkeypatch):
    with Client(secure.url, token=TOKENS["bob"], retries=0) as sdk:
        job = sdk.submit(two_disks("bob's via the SDK"))
        assert job.id in [j.id for j in sdk.jobs()]
        job.cancel()
    with Client(secure.url, token=TOKENS["alice"], retries=0) as sdk:
        assert job.id not in [j.id for j in sdk.jobs()]
        with pytest.raises(NotFound):
            sdk.job(job.id)
    monkeypatch.delenv("MPM_TOKEN", raising=False)
    with Client(secure.url, retries=0) as sdk, pytest.raises(Unauthorized):
        sdk.validate(two_disks())
    monkeypatch.setenv("MPM_TOKEN", TOKENS["bob"])  # the CLI and SDK default
    with Client(secure.url, retries=0) as sdk:
        assert sdk.job(job.id).id == job.id
    listed = subprocess.run([*MPM, "jobs", "--server", secure.url, "--token", TOKENS["alice"], "--json"],
                            capture_output=True, text=True, timeout=60)
    assert listed.returncode == 0, listed.stderr
    assert job.id not in listed.stdout


def test_no_token_in_the_logs(secure, alice):
    alice.get("/v1/jobs", params={"limit": 1})
    log = secure.log_path.read_text(errors="replace")
    assert "GET /v1/jobs?limit=1" in log  # the access log is on: the requests are there...
    for token in TOKENS.values():
        assert token not in log  # ...their tokens are not
    assert "API tokens for 3 owner(s)" in log  # what `mpm serve` says at start


def test_serve_refuses_a_bad_token_setting(tmp_path):
    env = {"MPM_API_TOKENS": "alice:short-secret", "MPM_DATA_DIR": str(tmp_path), "PATH": "/usr/bin:/bin"}
    done = subprocess.run([*MPM, "serve", "--no-worker", "--port", "1"], env=env,
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 1
    assert "MPM_API_TOKENS entry 1 (owner alice)" in done.stderr
    assert "short-secret" not in done.stderr + done.stdout


def test_without_tokens_serve_says_it_listens_on_localhost_only(tmp_path):
    """`mpm serve` says who can reach it before it binds; here the port is taken,
    so it stops right after saying so."""
    env = {"MPM_DATA_DIR": str(tmp_path), "PATH": "/usr/bin:/bin", "MPM_REDIS_URL": "redis://127.0.0.1:1/0"}
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        done = subprocess.run([*MPM, "serve", "--no-worker", "--port", str(taken.getsockname()[1])],
                              env=env, capture_output=True, text=True, timeout=60)
    assert "http://127.0.0.1:" in done.stderr
    assert "no MPM_API_TOKENS: listening on 127.0.0.1 only" in done.stderr

