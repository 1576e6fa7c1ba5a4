"""Sweeps, webhooks and the solver's log against the real stack (embedded Redis, two
workers, the API) and a webhook receiver on loopback (issue 21)."""
from __future__ import annotations

import hashlib
import hmac
import json
import time

import pytest

from service_support import WEBHOOK_SECRET, two_disks, wait_for_status, wait_until
from webhook_receiver import Receiver

pytestmark = pytest.mark.usefixtures("no_jobs_left")

SHORT = two_disks("sweep", end=0.05)
MODULUS = "/materials/rubber/youngs_modulus"


def _signed(request: dict) -> bool:
    expected = "sha256=" + hmac.new(WEBHOOK_SECRET.encode(), request["body"], hashlib.sha256).hexdigest()
    return hmac.compare_digest(request["headers"]["x-mpm-signature"], expected)


def test_a_grid_sweep_runs_one_job_per_combination_and_posts_once(api):
    with Receiver() as receiver:
        answer = api.post("/v1/sweeps", json={
            "scene": SHORT, "mode": "grid", "callback_url": receiver.url + "/sweep",
            "parameters": {MODULUS: [1000, 2000], "/time/end": [0.02, 0.04]}})
        assert answer.status_code == 202, answer.text
        sweep = answer.json()
        assert [job["parameters"] for job in sweep["jobs"]] == [
            {MODULUS: 1000, "/time/end": 0.02}, {MODULUS: 1000, "/time/end": 0.04},
            {MODULUS: 2000, "/time/end": 0.02}, {MODULUS: 2000, "/time/end": 0.04}]
        for job in sweep["jobs"]:
            record = wait_for_status(api, job["id"])
            assert record["status"] == "succeeded" and record["sweep"] == sweep["id"]
            scene = api.get(f"/v1/jobs/{job['id']}/scene").json()
            assert scene["materials"]["rubber"]["youngs_modulus"] == job["parameters"][MODULUS]
            assert scene["time"]["end"] == job["parameters"]["/time/end"]
        done = api.get(f"/v1/sweeps/{sweep['id']}").json()
        assert done["status"] == "finished" and done["progress"] == 1.0
        assert done["counts"]["succeeded"] == 4
        assert [job["status"] for job in done["jobs"]] == ["succeeded"] * 4
        wait_until(lambda: receiver.requests, 30, "the sweep's webhook")
        time.sleep(2)  # a second delivery would come within the sender's beat
        assert len(receiver.requests) == 1
        posted = receiver.requests[0]
        assert posted["path"] == "/sweep" and _signed(posted)
        assert posted["headers"]["x-mpm-event"] == "sweep.finished"
        assert json.loads(posted["body"])["counts"]["succeeded"] == 4
        assert sweep["id"] in [s["id"] for s in api.get("/v1/sweeps").json()["sweeps"]]
        assert api.delete(f"/v1/sweeps/{sweep['id']}").status_code == 204
        assert api.get(f"/v1/sweeps/{sweep['id']}").status_code == 404
        assert all(api.get(f"/v1/jobs/{job['id']}").status_code == 404 for job in sweep["jobs"])


def test_a_zip_sweep_is_validated_whole_before_anything_is_queued(api):
    before = api.get("/v1/jobs", params={"limit": 500}).json()["jobs"]
    bad = api.post("/v1/sweeps", json={"scene": SHORT, "mode": "zip",
                                       "parameters": {MODULUS: [1000, -5, 3000], "/time/end": [0.02, 0.03, 0.04]}})
    assert bad.status_code == 422, bad.text
    detail = bad.json()["error"]["details"][0]
    assert detail["path"] == f"parameters.{MODULUS}" and detail["combination"] == 1
    assert detail["values"] == {MODULUS: -5, "/time/end": 0.03} and "> 0" in detail["message"]
    for body, path, words in (
            ({"parameters": {"/materials/steel/density": [1]}}, "parameters./materials/steel/density", "no 'steel'"),
            ({"parameters": {"time/end": [1]}}, "parameters.time/end", "starts with '/'"),
            ({"parameters": {MODULUS: [1, 2], "/time/end": [1]}, "mode": "zip"}, "parameters", "one length"),
            ({"parameters": {MODULUS: list(range(1, 40)), "/time/end": list(range(1, 40))}}, "parameters",
             "MPM_MAX_SWEEP_JOBS")):
        answer = api.post("/v1/sweeps", json={"scene": SHORT, **body})
        assert answer.status_code == 422, answer.text
        assert answer.json()["error"]["details"][0]["path"] == path
        assert words in answer.json()["error"]["details"][0]["message"]
    assert api.get("/v1/jobs", params={"limit": 500}).json()["jobs"] == before  # nothing queued


def test_a_sweep_is_cancelled_whole(api):
    sweep = api.post("/v1/sweeps", json={"scene": two_disks("long", end=3000.0),
                                         "parameters": {MODULUS: [1000, 1100, 1200]}}).json()
    assert api.delete(f"/v1/sweeps/{sweep['id']}").status_code == 409  # not finished
    cancelled = api.post(f"/v1/sweeps/{sweep['id']}/cancel")
    assert cancelled.status_code == 202
    for job in sweep["jobs"]:
        assert wait_for_status(api, job["id"], timeout=60)["status"] == "cancelled"
    assert api.get(f"/v1/sweeps/{sweep['id']}").json()["counts"]["cancelled"] == 3


def test_a_job_webhook_is_signed_and_retried_until_it_is_taken(api):
    with Receiver(fail_first=2) as receiver:
        job = api.post("/v1/jobs", json={"scene": SHORT, "callback_url": receiver.url + "/hook"}).json()
        final = wait_for_status(api, job["id"])
        wait_until(lambda: len(receiver.requests) >= 3, 30, "three tries (two refused)")
        time.sleep(2)
        assert len(receiver.requests) == 3  # delivered on the third try, not again
        for request in receiver.requests:
            assert _signed(request) and request["headers"]["x-mpm-event"] == "job.finished"
            posted = json.loads(request["body"])
            assert posted["id"] == job["id"] and posted["status"] == final["status"] == "succeeded"


def test_a_webhook_that_never_succeeds_is_tried_five_times(api):
    with Receiver(fail_first=100) as receiver:
        job = api.post("/v1/jobs", json={"scene": SHORT, "callback_url": receiver.url}).json()
        wait_for_status(api, job["id"])
        wait_until(lambda: len(receiver.requests) >= 5, 60, "five tries")  # 1+2+4+8 s of backoff
        time.sleep(20)  # a sixth would have come after 16 s
        assert len(receiver.requests) == 5


@pytest.mark.parametrize("url,words", [
    ("http://10.0.0.1/hook", "not allowed by MPM_WEBHOOK_ALLOW"),
    ("http://169.254.169.254/latest/meta-data", "not allowed by MPM_WEBHOOK_ALLOW"),
    ("http://[::ffff:10.0.0.1]/x", "not allowed by MPM_WEBHOOK_ALLOW"),
    ("file:///etc/passwd", "http:// or https://"),
    ("http://user:pw@127.0.0.1/x", "credentials"),
    ("http://127.0.0.1:99999/x", "not a URL"),
])
def test_a_callback_to_a_host_not_allowed_is_refused(api, url, words):
    answer = api.post("/v1/jobs", json={"scene": SHORT, "callback_url": url})
    assert answer.status_code == 422, answer.text
    detail = answer.json()["error"]["details"][0]
    assert detail["path"] == "callback_url" and words in detail["message"]


def test_the_log_is_read_from_a_line_on(api, stack):
    job = api.post("/v1/jobs", json={"scene": SHORT}).json()
    wait_for_status(api, job["id"])
    whole = api.get(f"/v1/jobs/{job['id']}/log")
    assert whole.status_code == 200 and whole.headers["content-type"].startswith("text/plain")
    on_disk = (stack.data_dir / "jobs" / job["id"] / "solver.log").read_text()
    assert whole.text == on_disk and on_disk.count("\n") >= 1
    assert str(stack.data_dir) not in whole.text and '"result_path": "result.h5"' in whole.text   # issue 49
    assert int(whole.headers["x-mpm-next-line"]) == on_disk.count("\n")
    assert whole.headers["x-mpm-job-status"] == "succeeded"
    rest = api.get(f"/v1/jobs/{job['id']}/log", params={"since": 1})
    assert rest.text == "".join(on_disk.splitlines(keepends=True)[1:])
    past = api.get(f"/v1/jobs/{job['id']}/log", params={"since": 10**6})
    assert past.text == "" and past.headers["x-mpm-next-line"] == str(10**6)
    assert api.get(f"/v1/jobs/{job['id']}/log", params={"since": -1}).status_code == 422


def test_a_job_is_found_by_a_unique_prefix(api):
    job = api.post("/v1/jobs", json={"scene": SHORT}).json()
    found = api.get("/v1/jobs", params={"id_prefix": job["id"][:8]}).json()["jobs"]
    assert [j["id"] for j in found] == [job["id"]]
    assert api.get("/v1/jobs", params={"id_prefix": "zz*"}).status_code == 422
