"""The API without running jobs: validation (every error with its path), limits,
error bodies, examples, schema, health. Against the real stack (uvicorn + Redis)."""
from __future__ import annotations

import json
import os
from dataclasses import asdict
from pathlib import Path

import httpx
import pytest
import redis

from solver.karamelo import translate_file

from service_support import MPM, Process, answers, free_port, two_disks, wait_until


def _mutate(change):
    scene = two_disks()
    change(scene)
    return scene


# (name, change to a valid scene, the path the error must name, a word of the message)
BAD_SCENES = [
    ("dimension", lambda s: s.update(dimension=4), "dimension", "1, 2 or 3"),
    ("negative density", lambda s: s["materials"]["rubber"].update(density=-1),
     "materials.rubber.density", "> 0"),
    ("zero radius", lambda s: s["bodies"][1]["geometry"].update(radius=0),
     "bodies[1].geometry.radius", "> 0"),
    ("unknown key", lambda s: s.update(colour="red"), "colour", "unknown key"),
    ("unknown material", lambda s: s["bodies"][0].update(material="steel"),
     "bodies[0].material", "steel"),
    ("missing end time", lambda s: s["time"].pop("end"), "time.end", "required"),
    ("code in an expression", lambda s: s["bodies"][0].update(initial_velocity=["__import__('os')", 0]),
     "bodies[0].initial_velocity[0]", "not allowed"),
    ("poisson ratio 0.5", lambda s: s["materials"]["rubber"].update(poisson_ratio=0.5),
     "materials.rubber.poisson_ratio", "< 0.5"),
    ("body outside the grid", lambda s: s["bodies"][0]["geometry"].update(center=[2, 2]),
     "bodies[0].geometry", "outside the grid"),
    ("vector length", lambda s: s["bodies"][0].update(initial_velocity=[1, 2, 3]),
     "bodies[0].initial_velocity", "2 components"),
    ("unknown geometry", lambda s: s["bodies"][0]["geometry"].update(type="torus"),
     "bodies[0].geometry.type", "torus"),
    # MPM_MAX_PARTICLES is 80000 in the test stack (the largest example, cold_spray_3d_quarter, has
    # 76,699 particles): 60 x 60 particles per cell give 101,892
    ("over the particle limit", lambda s: s["bodies"][0].update(particles_per_cell=60),
     "bodies", "MPM_MAX_PARTICLES"),
]


def _jobs_on_disk(stack) -> set[str]:
    jobs = stack.data_dir / "jobs"
    return set(os.listdir(jobs)) if jobs.exists() else set()


@pytest.mark.parametrize("name,change,path,words", BAD_SCENES, ids=[c[0] for c in BAD_SCENES])
def test_bad_scenes_are_refused_with_the_path(api, stack, name, change, path, words):
    scene = _mutate(change)
    answer = api.post("/v1/scenes/validate", json=scene)
    assert answer.status_code == 422, answer.text
    error = answer.json()["error"]
    assert error["code"] == "validation_failed"
    assert [d["path"] for d in error["details"]] == [path]
    assert words in error["details"][0]["message"]

    # the same scene as a job: the same error, and no trace of a job anywhere
    listed_before, files_before = api.get("/v1/jobs").json()["jobs"], _jobs_on_disk(stack)
    answer = api.post("/v1/jobs", json={"scene": scene})
    assert answer.status_code == 422
    assert answer.json()["error"]["details"] == error["details"]
    assert api.get("/v1/jobs").json()["jobs"] == listed_before
    assert _jobs_on_disk(stack) == files_before


def test_every_error_is_reported_at_once(api):
    def three_errors(s):
        s["materials"]["rubber"]["density"] = 0
        s["bodies"][1]["geometry"]["radius"] = -1
        s["time"]["end"] = -2
    details = api.post("/v1/scenes/validate", json=_mutate(three_errors)).json()["error"]["details"]
    assert sorted(d["path"] for d in details) == [
        "bodies[1].geometry.radius", "materials.rubber.density", "time.end"]


def test_limit_errors_name_the_setting(api):
    # 8 million steps: within the scene's own max_steps guard, over MPM_MAX_STEPS (5 million here)
    scene = _mutate(lambda s: s["time"].update(dt=1.25e-7))
    details = api.post("/v1/scenes/validate", json=scene).json()["error"]["details"]
    assert details == [{"path": "time", "limit": "MPM_MAX_STEPS", "message": details[0]["message"]}]
    assert "MPM_MAX_STEPS" in details[0]["message"]


BAD_JOB_REQUESTS = [
    ("no scene", {"processes": 1}, "scene"),
    ("scene not an object", {"scene": [1, 2]}, "scene"),
    ("zero processes", {"scene": two_disks(), "processes": 0}, "processes"),
    ("unknown key", {"scene": two_disks(), "priority": "high"}, "priority"),
]


@pytest.mark.parametrize("name,body,path", BAD_JOB_REQUESTS, ids=[c[0] for c in BAD_JOB_REQUESTS])
def test_bad_job_requests(api, name, body, path):
    answer = api.post("/v1/jobs", json=body)
    assert answer.status_code == 422
    assert [d["path"] for d in answer.json()["error"]["details"]] == [path]


def test_invalid_json_is_a_validation_error(api):
    answer = api.post("/v1/jobs", content=b'{"scene": ', headers={"content-type": "application/json"})
    assert answer.status_code == 422
    [detail] = answer.json()["error"]["details"]
    assert detail["path"] == "" and "JSON" in detail["message"]


# A comma missing after line 2's value: the parser stops at the next key, line 3, column 3
# (1-based, as json.JSONDecodeError counts); the same text on each route that reads JSON.
MISSING_COMMA = b'{\n  "dimension": 2\n  "name": "x"\n}'


@pytest.mark.parametrize("route", ["/v1/scenes/validate", "/v1/jobs", "/v1/sweeps"])
def test_json_syntax_errors_give_line_and_column(api, route):
    answer = api.post(route, content=MISSING_COMMA, headers={"content-type": "application/json"})
    assert answer.status_code == 422
    [detail] = answer.json()["error"]["details"]
    assert (detail["path"], detail["line"], detail["column"]) == ("", 3, 3)
    assert detail["message"] == "not valid JSON: line 3, column 3: Expecting ',' delimiter"


@pytest.mark.parametrize("route", ["/v1/jobs", "/v1/sweeps"])
def test_a_bare_scene_is_one_error_that_says_to_wrap_it(api, stack, route):
    files_before = _jobs_on_disk(stack)
    answer = api.post(route, json=two_disks())
    assert answer.status_code == 422
    [detail] = answer.json()["error"]["details"]
    assert detail["path"] == "" and '{"scene": <the scene>}' in detail["message"]
    assert "bare scene" in detail["message"] and "bodies" in detail["message"]
    assert _jobs_on_disk(stack) == files_before


def test_validate_names_a_wrapped_scene(api):
    answer = api.post("/v1/scenes/validate", json={"scene": two_disks()})
    assert answer.status_code == 422
    [detail] = answer.json()["error"]["details"]
    assert detail["path"] == "scene" and "takes the scene itself" in detail["message"]


def test_validate_answers_the_summary(api):
    answer = api.post("/v1/scenes/validate", json=two_disks())
    assert answer.status_code == 200, answer.text
    summary = answer.json()["summary"]
    # two disks of radius 0.15 on 0.05 cells with 2x2 particles per cell; a 20 x 20 cell grid
    assert summary["grid_nodes"] == 21 * 21
    assert summary["particles"] == sum(summary["particles_per_body"]) > 0
    assert summary["estimated_steps"] == 1000  # end 1.0 / dt 0.001
    assert summary["memory_bytes"] > 0 and summary["estimated_run_seconds"] > 0


KARAMELO = Path(__file__).resolve().parents[1] / "data" / "karamelo"


def test_a_karamelo_file_is_imported_with_its_left_out_lines(api):
    """The route answers what `mpm import karamelo` makes of the file: the same scene and lines."""
    path = KARAMELO / "Cantilever__2D__cantilever_force_tip.mpm"
    answer = api.post("/v1/scenes/import/karamelo", json={"text": path.read_text(), "name": path.name})
    assert answer.status_code == 200, answer.text
    expected = translate_file(path)
    assert answer.json()["scene"] == json.loads(json.dumps(expected.scene))
    assert answer.json()["untranslated"] == [asdict(item) for item in expected.untranslated]
    assert answer.json()["notes"] == [asdict(item) for item in expected.notes]
    assert api.post("/v1/scenes/validate", json=answer.json()["scene"]).status_code == 200


def test_a_karamelo_file_that_cannot_be_imported_names_its_line(api):
    text = (KARAMELO / "Vertical_bar__ULMPM__vertical_bar.mpm").read_text()
    answer = api.post("/v1/scenes/import/karamelo", json={"text": text})
    assert answer.status_code == 422
    [detail] = answer.json()["error"]["details"]
    assert detail["path"] == "text" and detail["message"].startswith("line 34:") and "old syntax" in detail["message"]


def test_a_body_over_the_size_limit_is_refused_with_413(api, stack):
    # MPM_MAX_BODY_BYTES is 100000 in the test stack
    scene = two_disks(name="x" * 200_000)
    before = _jobs_on_disk(stack)
    answer = api.post("/v1/jobs", json={"scene": scene})
    assert answer.status_code == 413
    assert answer.json()["error"]["details"]["limit"] == "MPM_MAX_BODY_BYTES"
    assert _jobs_on_disk(stack) == before


def test_a_chunked_body_over_the_limit_is_cut_off(api):
    def chunks():
        yield b'{"scene": {"name": "'
        for _ in range(30):
            yield b"x" * 10_000
        yield b'"}}'
    answer = api.post("/v1/scenes/validate", content=chunks(), headers={"content-type": "application/json"})
    assert answer.status_code == 413


JOB_ROUTES = (("GET", ""), ("POST", "/cancel"), ("DELETE", ""), ("GET", "/result.h5"),
              ("GET", "/preview.png"), ("GET", "/series"), ("GET", "/scene"))


@pytest.mark.parametrize("job_id", ["0b7d5e1c-2a8e-4a55-9d0f-7c1f3b8f6e21", "not-a-uuid",
                                    "0B7D5E1C2A8E4A559D0F7C1F3B8F6E21"])
def test_unknown_jobs_are_404_in_the_error_format(api, job_id):
    for method, tail in JOB_ROUTES:
        answer = api.request(method, f"/v1/jobs/{job_id}{tail}")
        assert answer.status_code == 404, (method, tail, answer.text)
        assert answer.json()["error"]["code"] == "not_found"


def test_no_path_traversal_through_a_job_id(api):
    for job_id in ("..%2F..%2F..%2Fetc", "..", "%2Fetc%2Fpasswd"):
        for method, tail in JOB_ROUTES:
            answer = api.request(method, f"/v1/jobs/{job_id}{tail}")
            assert answer.status_code in (404, 405), (job_id, method, tail, answer.text)
            assert set(answer.json()) == {"error"}


def test_list_rejects_a_bad_cursor_and_status(api):
    answer = api.get("/v1/jobs", params={"cursor": "!!"})
    assert answer.status_code == 422 and answer.json()["error"]["details"][0]["path"] == "cursor"
    answer = api.get("/v1/jobs", params={"status": "sleeping"})
    assert answer.status_code == 422 and answer.json()["error"]["details"][0]["path"] == "status"


def test_examples_schema_health_docs(api):
    examples = api.get("/v1/examples").json()["examples"]
    for example in examples:
        assert set(example) == {"name", "title", "dimension"}
        scene = api.get(f"/v1/examples/{example['name']}").json()
        assert api.post("/v1/scenes/validate", json=scene).status_code == 200, example["name"]
    missing = api.get("/v1/examples/no-such-example")
    assert missing.status_code == 404 and missing.json()["error"]["code"] == "not_found"

    schema = api.get("/v1/schema/scene").json()
    assert {"dimension", "bodies", "materials", "time"} <= set(schema["properties"])

    assert api.get("/healthz").json() == {"status": "ok"}
    ready = api.get("/readyz")
    assert ready.status_code == 200 and ready.json()["workers"] == 2
    health = api.get("/v1/health").json()
    assert health["workers"] == ["w1@test", "w2@test"] and set(health["warming"]) <= {"w1@test"}
    assert api.get("/docs").status_code == 200
    assert "/v1/jobs" in api.get("/openapi.json").json()["paths"]
    assert api.get("/").status_code == 200


def test_unknown_route_and_method(api):
    answer = api.get("/v1/nothing-here")
    assert answer.status_code == 404 and answer.json()["error"]["code"] == "not_found"
    answer = api.put("/v1/jobs")
    assert answer.status_code == 405 and "error" in answer.json()


def test_logs_are_json_lines(api, stack):
    api.get("/healthz")
    lines = [line for line in stack.api.log.read_text().splitlines() if line.startswith("{")]
    events = [json.loads(line) for line in lines]
    assert any(e["event"] == "api started" for e in events)


def test_quota_429_and_not_ready_without_workers(stack, tmp_path):
    """An API on a Redis database no worker serves: jobs stay queued, /readyz says why,
    and past MPM_MAX_CONCURRENT_JOBS a submission is refused without a trace."""
    port = free_port()
    env = {**stack.env, "MPM_REDIS_URL": stack.redis_url.rsplit("/", 1)[0] + "/3",
           "MPM_DATA_DIR": str(tmp_path), "MPM_MAX_CONCURRENT_JOBS": "2"}
    lonely = Process("api-no-workers", [*MPM, "serve", "--no-worker", "--port", str(port)],
                     env, tmp_path).start()
    url = f"http://127.0.0.1:{port}"
    try:
        wait_until(answers(url, "/healthz"), 60, "the second API", processes=(lonely,))
        with httpx.Client(base_url=url, timeout=30) as api:
            ready = api.get("/readyz")
            assert ready.status_code == 503 and ready.json()["error"]["details"]["workers"] == 0
            accepted = [api.post("/v1/jobs", json={"scene": two_disks(f"q{i}")}) for i in range(2)]
            assert [a.status_code for a in accepted] == [202, 202]
            refused = api.post("/v1/jobs", json={"scene": two_disks("one too many")})
            assert refused.status_code == 429
            assert refused.json()["error"]["details"]["limit"] == "MPM_MAX_CONCURRENT_JOBS"
            assert len(api.get("/v1/jobs").json()["jobs"]) == 2
            assert len(os.listdir(tmp_path / "jobs")) == 2
            # a cancelled job no longer counts
            api.post(f"/v1/jobs/{accepted[0].json()['id']}/cancel")
            assert api.post("/v1/jobs", json={"scene": two_disks("fits again")}).status_code == 202
    finally:
        lonely.stop()
        redis.Redis.from_url(env["MPM_REDIS_URL"]).flushdb()
