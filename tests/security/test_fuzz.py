"""Fuzzing the live API (with tokens): schemathesis generates requests from the
service's own OpenAPI document, valid and invalid, for every operation; hypothesis
generates arbitrary JSON for scenes and arbitrary text for expressions. Never a 5xx;
every refusal is in the error format, a 422 naming the paths, a 413 the limit; the
service is healthy afterwards. The numbers of examples are bounded to keep CI short."""
from __future__ import annotations

import json

import httpx
import pytest
import schemathesis
from hypothesis import HealthCheck, Phase, given, settings
from hypothesis import strategies as st

from secure_service import bearer
from service_support import two_disks

FUZZ_SETTINGS = dict(deadline=None, phases=[Phase.explicit, Phase.generate],
                     suppress_health_check=list(HealthCheck), derandomize=True)


@pytest.fixture
def fuzz(secure):
    with httpx.Client(base_url=secure.url, timeout=60, headers=bearer("fuzz")) as client:
        yield client
    with httpx.Client(base_url=secure.url, timeout=60, headers=bearer("fuzz")) as client:
        for job in client.get("/v1/jobs", params={"limit": 500}).json()["jobs"]:  # whatever got in
            client.post(f"/v1/jobs/{job['id']}/cancel")


def check_answer(status: int, body: bytes) -> None:
    assert status < 500, body[:500]
    if status >= 400:
        error = json.loads(body)["error"]
        assert set(error) == {"code", "message", "details"} and error["message"]
        if status == 422:
            assert error["details"] and all({"path", "message"} <= set(d) for d in error["details"])
        if status == 413:
            assert error["details"]["limit"] == "MPM_MAX_BODY_BYTES"


def test_no_operation_answers_5xx(secure, fuzz):
    """Every operation of the OpenAPI document, with generated parameters and bodies."""
    schema = schemathesis.openapi.from_url(f"{secure.url}/openapi.json", headers=bearer("fuzz"))
    operations = [result.ok() for result in schema.get_all_operations()]
    assert len(operations) >= 10

    for operation in operations:
        @given(case=operation.as_strategy())
        @settings(max_examples=8, **FUZZ_SETTINGS)
        def call(case):
            response = case.call(base_url=secure.url, headers=bearer("fuzz"))
            check_answer(response.status_code, response.content)
        call()


json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=False, allow_infinity=False)
    | st.text(max_size=20),
    lambda children: st.lists(children, max_size=4) | st.dictionaries(st.text(max_size=10), children, max_size=4),
    max_leaves=30)
SCENE_KEYS = ["version", "name", "dimension", "grid", "materials", "bodies", "time", "output",
              "boundary_conditions", "gravity", "method"]


@given(key=st.sampled_from(SCENE_KEYS), value=json_values)
@settings(max_examples=60, **FUZZ_SETTINGS)
def test_any_json_in_a_scene_field_is_answered_with_its_path(fuzz, key, value):
    scene = two_disks()
    scene[key] = value
    answer = fuzz.post("/v1/scenes/validate", json=scene)
    check_answer(answer.status_code, answer.content)
    assert answer.status_code in (200, 422)


@given(text=st.text(max_size=80) | st.from_regex(r"[-+*/() x0-9.e*]{1,60}", fullmatch=True))
@settings(max_examples=80, **FUZZ_SETTINGS)
def test_any_expression_is_compiled_or_refused_at_its_path(fuzz, text):
    scene = two_disks()
    scene["bodies"][0]["initial_velocity"] = [text, 0]
    scene["time"]["allow_unstable_dt"] = True   # a valid expression may be a speed the fixed dt cannot follow
    answer = fuzz.post("/v1/scenes/validate", json=scene)
    check_answer(answer.status_code, answer.content)
    assert answer.status_code in (200, 422)
    if answer.status_code == 422:
        assert [d["path"] for d in answer.json()["error"]["details"]] == ["bodies[0].initial_velocity[0]"]


def test_healthy_after_the_fuzzing(fuzz):
    assert fuzz.get("/healthz").status_code == 200
    assert fuzz.get("/readyz").status_code == 200
    assert fuzz.post("/v1/scenes/validate", json=two_disks()).status_code == 200
