"""A fluid scene through the service: the still-water example submitted over HTTP, run
by a worker, with its result and a pressure preview (shortened to finish in seconds)."""
from __future__ import annotations

import io

import h5py
import pytest

from service_support import wait_for_status

pytestmark = pytest.mark.usefixtures("no_jobs_left")


def test_still_water_runs_through_the_service_with_a_pressure_preview(api):
    scene = api.get("/v1/examples/still_water_2d").json()
    scene["time"]["end"] = 0.1
    scene["output"]["frames"] = 3
    answer = api.post("/v1/jobs", json={"scene": scene})
    assert answer.status_code == 202, answer.text
    job = answer.json()
    record = wait_for_status(api, job["id"], timeout=180)
    assert record["status"] == "succeeded", record
    assert record["error"] is None and record["progress"] == 1.0

    result = api.get(f"/v1/jobs/{job['id']}/result.h5")
    with h5py.File(io.BytesIO(result.content), "r") as h5:
        assert h5.attrs["status"] == "complete"
        assert {"pressure", "pressure_smoothed"} <= set(h5["frames/000002"].keys())
    preview = api.get(f"/v1/jobs/{job['id']}/preview.png", params={"field": "pressure"})
    assert preview.status_code == 200 and preview.content.startswith(b"\x89PNG")
