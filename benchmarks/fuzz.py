"""The long fuzzing run (not in CI) and the hostile-payload table of docs/reliability.md.

    python benchmarks/fuzz.py                       # 2000 schema-drawn scenes, the payload table
    python benchmarks/fuzz.py --examples 200        # shorter

It starts `mpm serve` with tokens as tests/security does (an embedded Redis, a worker,
the API on a free port, a temporary MPM_DATA_DIR), then

1. sends each payload class of issues 21 and 49 three times and reports its answer
   (status, the path the error names) and the median time of the three;
2. draws --examples scenes from the scene's JSON Schema (tests/security/scene_strategies.py:
   half whole scenes, half a valid scene with one key replaced), seeded, and POSTs each
   to /v1/scenes/validate: the answers by status, the latency p50 / p99 / max, the
   requests over 1 s, the 5xx, the bodies with a traceback or a server path, and the
   API's resident memory before and after.

It prints Markdown tables.
"""
from __future__ import annotations

import argparse
import collections
import json
import math
import statistics
import sys
import tempfile
import time
from pathlib import Path

import httpx
from hypothesis import HealthCheck, Phase, given, settings

ROOT = Path(__file__).resolve().parent.parent
for folder in ("tests/security", "tests/integration", "tests/clients"):
    sys.path.insert(0, str(ROOT / folder))
sys.path.insert(0, str(ROOT))   # before benchmarks/, whose service.py would hide the service package

import scene_strategies  # noqa: E402
from secure_service import SecureService, bearer  # noqa: E402
from service_support import two_disks  # noqa: E402


def _scene(change) -> dict:
    scene = two_disks()
    change(scene)
    return scene


def _star(scene: dict) -> None:
    n = 10_000
    scene["bodies"][0]["geometry"] = {"type": "polygon", "vertices": [
        [round((0.2 if i % 2 == 0 else 0.002) * math.cos(2 * math.pi * i / n) - 0.3, 6),
         round((0.2 if i % 2 == 0 else 0.002) * math.sin(2 * math.pi * i / n) - 0.3, 6)] for i in range(n)]}


def _circle(crossing: bool):
    def change(scene: dict) -> None:
        n = 10_000
        vertices = [[round(0.2 * math.cos(2 * math.pi * i / n) - 0.3, 6), round(0.2 * math.sin(2 * math.pi * i / n) - 0.3, 6)]
                    for i in range(n)]
        if crossing:
            vertices[10], vertices[5000] = vertices[5000], vertices[10]
        scene["bodies"][0]["geometry"] = {"type": "polygon", "vertices": vertices}
    return change


def _triangles(scene: dict) -> None:
    triangle = [[-0.3, -0.3], [-0.29, -0.3], [-0.3, -0.29]]
    scene["bodies"][0]["geometry"] = {"type": "union", "parts": [{"type": "polygon", "vertices": triangle}] * 4000}


SWEEP = {"scene": two_disks(), "parameters": {"/materials/rubber/youngs_modulus": [1000.0 + i for i in range(1000)]}}

# (payload class, the answer before issue 49 (its report), method, path, JSON body or (bytes, content type))
PAYLOADS = [
    ("output.frames = 10^9", '202, solver past 13 GB', "POST", "/v1/jobs", {"scene": _scene(lambda s: s.update(output={"frames": 10**9}))}),
    ("callback_url with CR/LF", '202; the webhook thread died at delivery', "POST", "/v1/jobs",
     {"scene": two_disks(), "callback_url": "http://127.0.0.1:9911/\r\nX-Injected: 1"}),
    ("callback_url gopher://", '422', "POST", "/v1/jobs", {"scene": two_disks(), "callback_url": "gopher://127.0.0.1:9911/"}),
    ("grid from -1e308 to 1e308", '500 (OverflowError)', "POST", "/v1/jobs",
     {"scene": _scene(lambda s: s["grid"].update(lower=[-1e308, -1e308], upper=[1e308, 1e308]))}),
    ("cell_size 1e300", '500 (OverflowError)', "POST", "/v1/jobs", {"scene": _scene(lambda s: s["grid"].update(cell_size=1e300))}),
    ("end / dt = 1e616", '-', "POST", "/v1/jobs", {"scene": _scene(lambda s: s["time"].update(end=1e308, dt=1e-308))}),
    ("10,000-vertex circle", '-', "POST", "/v1/scenes/validate", _scene(_circle(False))),
    ("10,000-vertex circle crossing itself", '-', "POST", "/v1/scenes/validate", _scene(_circle(True))),
    ("10,000-vertex star (O(n^2) edge pairs)", 'a 10,000-vertex polygon: 10.6 s to accept, 36.6 s to refuse', "POST", "/v1/scenes/validate", _scene(_star)),
    ("union of 4000 polygons", 'a union of 2000: 6.6 s', "POST", "/v1/scenes/validate", _scene(_triangles)),
    ("sweep of 1000 values", '429 after 2.5 s', "POST", "/v1/sweeps", SWEEP),
    ("a body seeding no particle", '202, run', "POST", "/v1/jobs",
     {"scene": _scene(lambda s: s["bodies"][1]["geometry"].update(radius=1e-4))}),
    ("5000-digit integer", '400, no position', "POST", "/v1/scenes/validate", (b'{"dimension": ' + b"7" * 5000 + b"}", "application/json")),
    ("text/plain body", "422 'Input should be a valid dictionary'", "POST", "/v1/jobs", (json.dumps({"scene": two_disks()}).encode(), "text/plain")),
    ("form body", "422 'Input should be a valid dictionary'", "POST", "/v1/jobs", (b"scene=%7B%7D", "application/x-www-form-urlencoded")),
]


def payload_table(client: httpx.Client, repeats: int = 3) -> list[str]:
    rows = ["| payload | before (issue 49) | answer | error names | median time |", "|---|---|---|---|---|"]
    for name, before, method, path, body in PAYLOADS:
        times, answer = [], None
        for _ in range(repeats):
            kwargs = ({"content": body[0], "headers": {"content-type": body[1]}} if isinstance(body, tuple)
                      else {"json": body})
            started = time.monotonic()
            answer = client.request(method, path, **kwargs)
            times.append(time.monotonic() - started)
        error = answer.json().get("error") or {} if answer.headers.get("content-type", "").startswith("application/json") else {}
        details = error.get("details")
        named = (", ".join(sorted({d.get("path") or "(body)" for d in details})) if isinstance(details, list)
                 else (details or {}).get("limit", "") if isinstance(details, dict) else "")
        rows.append(f"| {name} | {before} | {answer.status_code} | {named} | {1000 * statistics.median(times):.0f} ms |")
    return rows


def fuzz(service: SecureService, client: httpx.Client, examples: int) -> list[str]:
    schema = client.get("/v1/schema/scene").json()
    paths = [str(service.data_dir), str(ROOT), sys.prefix, "site-packages"]
    statuses, latencies, findings = collections.Counter(), [], []
    drawn = scene_strategies.scenes(schema) | scene_strategies.scene_parts(schema).map(
        lambda part: {**two_disks(), part[0]: part[1]})

    @given(scene=drawn)
    @settings(max_examples=examples, deadline=None, derandomize=True, database=None,
              suppress_health_check=list(HealthCheck), phases=[Phase.generate])
    def send(scene):
        started = time.monotonic()
        answer = client.post("/v1/scenes/validate", json=scene)
        latencies.append(time.monotonic() - started)
        statuses[answer.status_code] += 1
        text = answer.text
        if answer.status_code >= 500 or "Traceback" in text or any(p in text for p in paths) or latencies[-1] >= 1:
            findings.append((answer.status_code, round(latencies[-1], 3), json.dumps(scene)[:300]))

    before = rss(service.process.pid)
    started = time.monotonic()
    send()
    wall = time.monotonic() - started
    after = rss(service.process.pid)
    latencies.sort()
    pick = lambda q: latencies[min(len(latencies) - 1, int(q * len(latencies)))]  # noqa: E731
    rows = ["| quantity | value |", "|---|---|",
            f"| requests | {len(latencies)} in {wall:.0f} s |",
            f"| answers | {', '.join(f'{s}: {n}' for s, n in sorted(statuses.items()))} |",
            f"| latency p50 / p99 / max | {1000 * pick(0.5):.0f} / {1000 * pick(0.99):.0f} / {1000 * latencies[-1]:.0f} ms |",
            f"| findings (5xx, traceback, server path, >= 1 s) | {len(findings)} |",
            f"| API resident memory before -> after | {before:.0f} -> {after:.0f} MiB |"]
    return rows + [f"\nfinding: {finding}" for finding in findings[:20]]


def rss(pid: int) -> float:
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024
    return 0.0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--examples", type=int, default=2000, help="schema-drawn scenes to send (default 2000)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="mpm-fuzz-") as root:
        service = SecureService(Path(root)).start()
        try:
            with httpx.Client(base_url=service.url, timeout=120, headers=bearer("fuzz")) as client:
                print("\n".join(payload_table(client)))
                print()
                print("\n".join(fuzz(service, client, args.examples)))
        finally:
            service.stop()


if __name__ == "__main__":
    main()
