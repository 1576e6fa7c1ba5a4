"""A table of hostile inputs against the live service with tokens: each is answered
4xx in the error format, naming the field (or the rule) it breaks, quickly, and the
service is healthy and working afterwards."""
from __future__ import annotations

import json
import math
import time

import pytest

from service_support import two_disks

MAX_BODY = 300_000  # MPM_MAX_BODY_BYTES of the secure service (secure_service.py)


def _scene(change) -> dict:
    scene = two_disks()
    change(scene)
    return scene


def _velocity(expression: str):
    return lambda s: s["bodies"][0].update(initial_velocity=[expression, 0])


def _nested(depth: int) -> bytes:
    return b'{"scene": ' + b"[" * depth + b"]" * depth + b"}"


def _star_body(scene: dict) -> None:
    # 5000 spikes from near the centre to the rim: 25 million pairs of edges to check (36 s before)
    n = 10_000
    vertices = [[round((0.2 if i % 2 == 0 else 0.002) * math.cos(2 * math.pi * i / n) - 0.3, 6),
                 round((0.2 if i % 2 == 0 else 0.002) * math.sin(2 * math.pi * i / n) - 0.3, 6)] for i in range(n)]
    scene["bodies"][0]["geometry"] = {"type": "polygon", "vertices": vertices}


def _specks(scene: dict) -> None:
    # the 6400 bodies of which 6384 seeded nothing, scaled to the body limit
    scene["bodies"] = [{"name": f"b{i}", "material": "rubber", "geometry": {
        "type": "sphere", "center": [round(-0.45 + 0.023 * (i % 40), 3), round(-0.45 + 0.023 * (i // 40), 3)],
        "radius": 0.004 if i % 100 else 0.02}} for i in range(1500)]


# A 1 m cube of 1 cm cells (10^6 nodes, within MPM_MAX_GRID_NODES), filled with 100^3 particles a cell
TRILLION_PARTICLES = {
    "version": 1, "name": "trillion", "dimension": 3,
    "grid": {"lower": [0, 0, 0], "upper": [1, 1, 1], "cell_size": 0.01},
    "materials": {"m": {"model": "linear_elastic", "density": 1000, "youngs_modulus": 1e6, "poisson_ratio": 0.3}},
    "bodies": [{"name": "block", "material": "m", "particles_per_cell": 100,
                "geometry": {"type": "box", "lower": [0, 0, 0], "upper": [1, 1, 1]}}],
    "time": {"end": 0.01, "dt": 1e-4},   # below the stability limit of 1 cm cells (2.7e-4)
}

# (name, method, path, body: dict (sent as JSON) or bytes (sent as they are),
#  the status, the path the error must name ("" for the body as a whole), a word of the message)
HOSTILE = [
    ("deeply nested JSON", "POST", "/v1/jobs", _nested(100_000), 422, "", "MPM_MAX_JSON_DEPTH"),
    ("nested just past the limit", "POST", "/v1/scenes/validate",
     b'{"name": ' + b"[" * 64 + b"]" * 64 + b"}", 422, "", "MPM_MAX_JSON_DEPTH"),
    ("nested inside the limit, in a field", "POST", "/v1/scenes/validate",
     json.dumps(_scene(lambda s: s.update(name=[[[[[[1]]]]]]))).encode(), 422, "name", "string"),
    ("huge array body", "POST", "/v1/jobs", b'{"scene": [' + b"0," * 200_000 + b"0]}", 413, None, "bytes"),
    ("huge array in a field", "POST", "/v1/scenes/validate",
     _scene(lambda s: s["grid"].update(lower=[0.0] * 20_000)), 422, "grid.lower", "at most 3"),
    ("NaN literal", "POST", "/v1/scenes/validate",
     json.dumps(two_disks()).replace('"density": 1000', '"density": NaN').encode(), 422,
     "materials.rubber.density", "finite"),
    ("Infinity literal", "POST", "/v1/jobs",
     b'{"scene": ' + json.dumps(two_disks()).replace('"end": 1.0', '"end": Infinity').encode() + b"}",
     422, "time.end", "finite"),
    ("-Infinity as processes", "POST", "/v1/jobs",
     b'{"scene": ' + json.dumps(two_disks()).encode() + b', "processes": -Infinity}', 422, "processes", ""),
    ("attribute access", "POST", "/v1/scenes/validate", _scene(_velocity("x.__class__")), 422,
     "bodies[0].initial_velocity[0]", "attribute access is not allowed"),
    ("import", "POST", "/v1/scenes/validate", _scene(_velocity("__import__('os').system('true')")), 422,
     "bodies[0].initial_velocity[0]", "'__import__'"),
    ("import statement", "POST", "/v1/scenes/validate", _scene(_velocity("import os")), 422,
     "bodies[0].initial_velocity[0]", "unknown name 'import'"),
    ("dunder name", "POST", "/v1/scenes/validate", _scene(_velocity("__builtins__")), 422,
     "bodies[0].initial_velocity[0]", "unknown name '__builtins__'"),
    ("exponent bomb", "POST", "/v1/jobs", {"scene": _scene(_velocity("9**9**9"))}, 422,
     "bodies[0].initial_velocity[0]", "gives inf"),
    ("division by zero", "POST", "/v1/scenes/validate", _scene(_velocity("x + 1/0")), 422,
     "bodies[0].initial_velocity[0]", "gives inf"),
    ("overlong expression", "POST", "/v1/scenes/validate", _scene(_velocity("x+" * 20_000 + "x")), 422,
     "bodies[0].initial_velocity[0]", "longer than 1000"),
    ("deeply nested expression", "POST", "/v1/scenes/validate", _scene(_velocity("(" * 200 + "x" + ")" * 200)),
     422, "bodies[0].initial_velocity[0]", "nested too deeply"),
    ("10^12 particles", "POST", "/v1/jobs", {"scene": TRILLION_PARTICLES}, 422, "bodies", "MPM_MAX_PARTICLES"),
    ("a million particles per cell and axis", "POST", "/v1/jobs",
     {"scene": _scene(lambda s: s["bodies"][0].update(particles_per_cell=1_000_000))}, 422,
     "bodies[0].particles_per_cell", "100"),
    ("10^12 grid nodes", "POST", "/v1/jobs", {"scene": _scene(lambda s: s["grid"].update(cell_size=1e-6))},
     422, "grid", "MPM_MAX_GRID_NODES"),
    ("10^400 as an integer", "POST", "/v1/scenes/validate",
     json.dumps(two_disks()).replace('"particles_per_cell": 2', '"particles_per_cell": 1' + "0" * 400, 1).encode(),
     422, "bodies[0].particles_per_cell", ""),
    ("unicode control characters in a material name", "POST", "/v1/scenes/validate",
     _scene(lambda s: s["bodies"][0].update(material="st\u202eeel\u0000")), 422, "bodies[0].material", "st"),
    ("not JSON at all", "POST", "/v1/jobs", b"\xff\xfe\x00binary", 422, "", "JSON"),
    ("a list for the request", "POST", "/v1/jobs", [1, 2, 3], 422, "", ""),
    # issue 49
    ("a billion frames", "POST", "/v1/jobs",
     {"scene": _scene(lambda s: s.update(output={"frames": 10**9}))}, 422, "output.frames", "time steps"),
    ("a grid from -1e308 to 1e308", "POST", "/v1/jobs",
     {"scene": _scene(lambda s: s["grid"].update(lower=[-1e308, -1e308], upper=[1e308, 1e308]))}, 422, "grid",
     "not a finite number of cells"),
    ("cells of 1e300", "POST", "/v1/scenes/validate", _scene(lambda s: s["grid"].update(cell_size=1e300)), 422,
     "bodies[0]", "seeds no particle"),
    ("end / dt of 1e616", "POST", "/v1/scenes/validate", _scene(lambda s: s["time"].update(end=1e308, dt=1e-308)),
     422, "time.dt", "max_steps"),
    ("a body smaller than its particle spacing", "POST", "/v1/jobs",
     {"scene": _scene(lambda s: s["bodies"][1]["geometry"].update(radius=1e-4))}, 422, "bodies[1]",
     "'disk2' seeds no particle"),
    ("1500 bodies, most seeding no particle", "POST", "/v1/jobs", {"scene": _scene(_specks)}, 422, "bodies",
     "more bodies seed no particle"),
    ("a 10,000-vertex star polygon", "POST", "/v1/scenes/validate", _scene(_star_body), 422,
     "bodies[0].geometry.vertices", "too complex"),
    ("a 5000-digit integer", "POST", "/v1/scenes/validate",
     b'{"version": 1,\n "dimension": ' + b"7" * 5000 + b"}", 422, "", "line 2, column 15"),
    ("a callback URL with CR/LF", "POST", "/v1/jobs",
     {"scene": two_disks(), "callback_url": "http://127.0.0.1:9911/\r\nX-Injected: 1"}, 422, "callback_url",
     "control characters"),
    ("a callback URL of another scheme", "POST", "/v1/jobs",
     {"scene": two_disks(), "callback_url": "gopher://127.0.0.1:9911/"}, 422, "callback_url", "http://"),
    ("path-like job id", "GET", "/v1/jobs/..%2F..%2F..%2Fetc%2Fpasswd", None, 404, None, ""),
    ("dot-dot job id", "DELETE", "/v1/jobs/%2E%2E", None, 404, None, ""),
    ("job id with a NUL", "GET", "/v1/jobs/%00", None, 404, None, ""),
    ("path-like example name", "GET", "/v1/examples/..%2F..%2Fpyproject", None, 404, None, ""),
    ("a huge limit", "GET", "/v1/jobs?limit=100000000000000000000", None, 422, "limit", ""),
    ("a forged cursor", "GET", "/v1/jobs?cursor=" + "A" * 5000, None, 422, "cursor", ""),
    ("a hostile preview field", "GET", "/v1/jobs/0b7d5e1c-2a8e-4a55-9d0f-7c1f3b8f6e21/preview.png"
     "?field=../../etc", None, 422, "field", ""),
]


@pytest.mark.parametrize("name,method,path,body,status,field,words", HOSTILE, ids=[c[0] for c in HOSTILE])
def test_hostile_input_is_refused_cleanly(alice, name, method, path, body, status, field, words):
    started = time.monotonic()
    if body is None:
        answer = alice.request(method, path)
    elif isinstance(body, bytes):
        answer = alice.request(method, path, content=body, headers={"content-type": "application/json"})
    else:
        answer = alice.request(method, path, json=body)
    elapsed = time.monotonic() - started
    assert answer.status_code == status, answer.text[:500]
    error = answer.json()["error"]
    assert set(error) == {"code", "message", "details"}
    if field is not None:
        paths = [d["path"] for d in error["details"]]
        assert field in paths, paths
        assert any(words in d["message"] for d in error["details"] if d["path"] == field), error
    else:
        assert words in error["message"]
    assert len(answer.content) < 20_000  # a huge input is not echoed back
    assert elapsed < 10, f"{name} took {elapsed:.1f} s"  # refused before any work is done

    # healthy afterwards: it answers, is ready, and still validates a good scene
    assert alice.get("/healthz").status_code == 200
    assert alice.get("/readyz").status_code == 200
    assert alice.post("/v1/scenes/validate", json=two_disks()).status_code == 200


def _cube(cell_size: float, ppc: int = 2) -> dict:
    # the fixed dt is far above these cells' stability limit: allowed, the size limits are the point
    return {**TRILLION_PARTICLES, "grid": {**TRILLION_PARTICLES["grid"], "cell_size": cell_size},
            "bodies": [{**TRILLION_PARTICLES["bodies"][0], "particles_per_cell": ppc}],
            "time": {**TRILLION_PARTICLES["time"], "allow_unstable_dt": True}}


def _many_parts(scene: dict) -> None:
    disk = scene["bodies"][0]["geometry"]
    scene["bodies"][0]["geometry"] = {"type": "union", "parts": [disk] * 2000}


# Scenes whose size is absurd (issue 21: 1 nm cells on a 1 m grid took 36-82 s to refuse):
# (name, path, request body, the paths the error must name)
HUGE = [
    ("1 nm cells, 2D, submitted", "/v1/jobs", {"scene": _scene(lambda s: s["grid"].update(cell_size=1e-9))},
     {"grid", "bodies"}),
    ("1 nm cells, 2D, validated", "/v1/scenes/validate", _scene(lambda s: s["grid"].update(cell_size=1e-9)),
     {"grid", "bodies"}),
    ("1 nm cells, 3D cube, submitted", "/v1/jobs", {"scene": _cube(1e-9)}, {"grid", "bodies"}),
    ("1 um cells, 3D, 100 particles a cell and axis", "/v1/scenes/validate", _cube(1e-6, 100), {"grid", "bodies"}),
    ("a union of 2000 disks on 1 mm cells", "/v1/jobs",
     {"scene": _scene(lambda s: (_many_parts(s), s["grid"].update(cell_size=1e-3)))}, {"bodies"}),
]


@pytest.mark.parametrize("name,path,body,fields", HUGE, ids=[c[0] for c in HUGE])
def test_a_huge_scene_is_refused_within_a_second(alice, name, path, body, fields):
    before = alice.get("/v1/jobs").json()["jobs"]
    started = time.monotonic()
    answer = alice.post(path, json=body)
    elapsed = time.monotonic() - started
    assert answer.status_code == 422, answer.text[:500]
    details = answer.json()["error"]["details"]
    assert {d["path"] for d in details} == fields
    assert all(d["limit"] in ("MPM_MAX_GRID_NODES", "MPM_MAX_PARTICLES") for d in details), details
    assert elapsed < 1.0, f"{name} took {elapsed:.2f} s"
    assert alice.get("/v1/jobs").json()["jobs"] == before  # nothing queued


@pytest.mark.parametrize("content_type,body", [
    ("text/plain", json.dumps({"scene": two_disks()}).encode()),
    ("application/x-www-form-urlencoded", b"scene=%7B%7D"),
    ("multipart/form-data; boundary=x", b'--x\r\nContent-Disposition: form-data; name="scene"\r\n\r\n{}\r\n--x--'),
    (None, json.dumps({"scene": two_disks()}).encode()),
])
def test_a_body_that_is_not_json_by_its_type_is_a_415(alice, content_type, body):
    headers = {"content-type": content_type} if content_type else {}
    answer = alice.post("/v1/jobs", content=body, headers=headers)
    assert answer.status_code == 415, answer.text
    assert "send application/json" in answer.json()["error"]["message"]


def test_a_sweep_over_the_quota_is_refused_before_its_scenes_are_validated(alice):
    before = alice.get("/v1/jobs").json()["jobs"]
    started = time.monotonic()
    answer = alice.post("/v1/sweeps", json={"scene": two_disks(), "parameters": {
        "/materials/rubber/youngs_modulus": [1000.0 + i for i in range(1000)]}})
    elapsed = time.monotonic() - started
    assert answer.status_code == 429, answer.text
    assert answer.json()["error"]["details"]["limit"] in ("MPM_QUOTA_ACTIVE_JOBS", "MPM_QUOTA_QUEUED_JOBS")
    assert elapsed < 1.0, f"took {elapsed:.2f} s"   # 2.5 s before: every combination was validated first
    assert alice.get("/v1/jobs").json()["jobs"] == before


def test_unicode_names_are_kept_as_they_are(alice):
    scene = two_disks("模拟 — ünïcødé 🚀")
    scene["materials"] = {"gummi-ß": scene["materials"]["rubber"]}
    for body in scene["bodies"]:
        body["material"] = "gummi-ß"
    answer = alice.post("/v1/jobs", json={"scene": scene})
    assert answer.status_code == 202, answer.text
    job = answer.json()
    try:
        assert alice.get(f"/v1/jobs/{job['id']}").json()["name"] == "模拟 — ünïcødé 🚀"
        assert "gummi-ß" in alice.get(f"/v1/jobs/{job['id']}/scene").json()["materials"]
    finally:
        alice.post(f"/v1/jobs/{job['id']}/cancel")
