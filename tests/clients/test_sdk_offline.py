"""The SDK against a scripted fake of the HTTP API: error mapping, retries, paging, downloads, waiting."""
from __future__ import annotations

import asyncio
import json
import subprocess
import sys
from pathlib import Path

import httpx
import pytest

from mpm_client import (
    ApiError,
    Client,
    Conflict,
    JobCancelled,
    JobFailed,
    NotFound,
    ServiceUnavailable,
    Unauthorized,
    ValidationFailed,
    WaitTimeout,
)
from mpm_client._api import Retrier
from mpm_client.progress import format_duration, format_progress
from mpm_client.models import JobRecord
from sdk_fakes import BASE, JOB_ID, error, job_record, sent_json

JOB = f"/v1/jobs/{JOB_ID}"
SCENE = {"version": 1, "name": "two-disks", "dimension": 2}


# -- error mapping -------------------------------------------------------------------


@pytest.mark.parametrize("status, code, cls", [
    (401, "unauthorized", Unauthorized),
    (403, "forbidden", Unauthorized),
    (404, "not_found", NotFound),
    (409, "conflict", Conflict),
    (500, "internal", ApiError),
])
def test_error_answers_become_typed_errors_without_retry(fake, client, status, code, cls):
    fake.on("GET", JOB, error(status, code, f"message {status}", {"hint": 1}))
    with pytest.raises(cls) as caught:
        client.job(JOB_ID)
    assert type(caught.value) is cls
    assert (caught.value.status_code, caught.value.code) == (status, code)
    assert caught.value.message == f"message {status}"
    assert caught.value.details == {"hint": 1}
    assert len(fake.calls("GET", JOB)) == 1  # 4xx and 500 are never retried


def test_validation_failed_carries_every_path_and_message(fake, client):
    details = [{"path": "bodies[1].geometry.radius", "message": "must be > 0"},
               {"path": "materials.rubber.poisson_ratio", "message": "must be < 0.5"}]
    fake.on("POST", "/v1/scenes/validate", error(422, "validation_failed", "the scene is invalid", details))
    with pytest.raises(ValidationFailed) as caught:
        client.validate(SCENE)
    assert caught.value.errors == details
    assert "bodies[1].geometry.radius: must be > 0" in str(caught.value)
    assert "materials.rubber.poisson_ratio: must be < 0.5" in str(caught.value)


def test_an_error_without_a_json_body_still_names_the_request(fake, client):
    fake.on("GET", "/v1/examples", httpx.Response(404, text="nope"))
    with pytest.raises(NotFound, match="GET /v1/examples answered 404"):
        client.examples()


# -- retries -------------------------------------------------------------------------


def test_503_and_502_are_retried_until_an_answer_comes(fake, client):
    fake.on("GET", JOB, error(503, "unavailable", "no worker"), httpx.Response(502),
            httpx.Response(200, json=job_record("running")))
    assert client.job(JOB_ID).record.status == "running"
    assert len(fake.calls("GET", JOB)) == 3


def test_retries_run_out_into_service_unavailable(fake):
    fake.on("GET", JOB, httpx.Response(504))
    with Client(BASE, retries=2, backoff=0.0, transport=httpx.MockTransport(fake)) as client:
        with pytest.raises(ServiceUnavailable) as caught:
            client.job(JOB_ID)
    assert caught.value.status_code == 504
    assert len(fake.calls("GET", JOB)) == 3  # the first try and two retries


def test_connection_errors_are_retried_for_any_method(fake, client):
    refused = httpx.ConnectError("connection refused")
    fake.on("POST", "/v1/jobs", refused, refused, httpx.Response(202, json=job_record()))
    assert client.submit(SCENE).id == JOB_ID
    assert len(fake.calls("POST", "/v1/jobs")) == 3


def test_a_post_that_may_have_arrived_is_not_sent_twice(fake, client):
    fake.on("POST", "/v1/jobs", httpx.ReadError("connection reset"), httpx.Response(202, json=job_record()))
    with pytest.raises(ServiceUnavailable, match="connection reset"):
        client.submit(SCENE)
    assert len(fake.calls("POST", "/v1/jobs")) == 1


def test_a_get_whose_answer_broke_off_is_retried(fake, client):
    fake.on("GET", JOB, httpx.ReadError("connection reset"), httpx.Response(200, json=job_record()))
    assert client.job(JOB_ID).id == JOB_ID


def test_unreachable_service_raises_service_unavailable_without_status(fake):
    fake.on("GET", "/v1/examples", httpx.ConnectError("connection refused"))
    with Client(BASE, retries=1, backoff=0.0, transport=httpx.MockTransport(fake)) as client:
        with pytest.raises(ServiceUnavailable) as caught:
            client.examples()
    assert caught.value.status_code is None
    assert len(fake.requests) == 2


def test_backoff_doubles_and_honours_retry_after():
    retrier = Retrier("GET", retries=5, backoff=1.0, max_backoff=3.0)
    delays = [retrier.after_error(httpx.ConnectError("refused")) for _ in range(3)]
    # jitter draws each delay from [half, all] of 1, 2, 4 (capped at 3)
    assert 0.5 <= delays[0] <= 1.0 and 1.0 <= delays[1] <= 2.0 and 1.5 <= delays[2] <= 3.0
    answer = httpx.Response(503, headers={"Retry-After": "2"}, request=httpx.Request("GET", BASE))
    assert retrier.after_response(answer) == 2.0


# -- requests ------------------------------------------------------------------------


def test_submit_sends_scene_processes_and_token(fake, client):
    fake.on("POST", "/v1/jobs", httpx.Response(202, json=job_record()))
    job = client.submit(SCENE, processes=2)
    request = fake.calls("POST", "/v1/jobs")[0]
    assert sent_json(request) == {"scene": SCENE, "processes": 2}  # no nodes unless asked: the service's default
    assert request.headers["authorization"] == "Bearer secret"
    assert job.record.summary.particles == 416


def test_submit_asks_for_slurm_nodes_beside_processes(fake, client):
    fake.on("POST", "/v1/jobs", httpx.Response(202, json=job_record()))
    client.submit(SCENE, processes=4, nodes=2)
    assert sent_json(fake.calls("POST", "/v1/jobs")[0]) == {"scene": SCENE, "processes": 4, "nodes": 2}


def test_submit_reads_a_file_json_text_or_a_pydantic_model(fake, client, tmp_path):
    from pydantic import BaseModel

    class Scene(BaseModel):
        version: int
        name: str
        dimension: int
        axisymmetric: bool | None = None

    fake.on("POST", "/v1/jobs", httpx.Response(202, json=job_record()))
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(SCENE))
    for scene in (path, str(path), json.dumps(SCENE), Scene(**SCENE)):
        client.submit(scene)
    assert [sent_json(r)["scene"] for r in fake.requests] == [SCENE] * 4


def test_submit_imports_a_karamelo_file_and_warns_of_its_lines(fake, client):
    from mpm_client.scenes import KarameloImportWarning
    from solver.karamelo import translate_file

    data = Path(__file__).resolve().parents[1] / "data" / "karamelo"
    fake.on("POST", "/v1/jobs", httpx.Response(202, json=job_record()))
    with pytest.warns(KarameloImportWarning) as caught:
        client.submit(data / "Cantilever__2D__cantilever_force_tip.mpm")
    assert sent_json(fake.requests[0])["scene"] == translate_file(data / "Cantilever__2D__cantilever_force_tip.mpm").scene
    assert any(":46: note: fix(fEnd, force_nodes" in str(w.message) for w in caught)
    with pytest.raises(ValueError, match="vertical_bar.mpm: cannot import the Karamelo file: line 34: .* old syntax"):
        client.submit(data / "Vertical_bar__ULMPM__vertical_bar.mpm")


def test_a_missing_or_broken_scene_file_is_named(client, tmp_path):
    with pytest.raises(FileNotFoundError, match="nowhere.json"):
        client.submit(tmp_path / "nowhere.json")
    broken = tmp_path / "broken.json"
    broken.write_text('{"version": 1,')
    with pytest.raises(ValueError, match=r"broken.json is not valid JSON: line 1"):
        client.submit(broken)


def test_jobs_follows_every_page(fake, client):
    pages = {
        None: {"jobs": [job_record(id="a"), job_record(id="b")], "next_cursor": "c1"},
        "c1": {"jobs": [job_record(id="c")], "next_cursor": "c2"},
        "c2": {"jobs": [], "next_cursor": None},
    }
    fake.on("GET", "/v1/jobs", lambda request: httpx.Response(200, json=pages[request.url.params.get("cursor")]))
    assert [job.id for job in client.jobs(status="running", limit=2)] == ["a", "b", "c"]
    assert all(r.url.params["status"] == "running" and r.url.params["limit"] == "2" for r in fake.requests)
    assert len(fake.requests) == 3


def test_examples_and_example(fake, client):
    fake.on("GET", "/v1/examples", httpx.Response(200, json={"examples": [
        {"name": "two_disks", "title": "Two elastic disks", "dimension": 2}]}))
    fake.on("GET", "/v1/examples/two_disks", httpx.Response(200, json=SCENE))
    assert [(e.name, e.dimension) for e in client.examples()] == [("two_disks", 2)]
    assert client.example("two_disks") == SCENE


def test_cancel_posts_and_refreshes(fake, client):
    fake.on("GET", JOB, httpx.Response(200, json=job_record("running")),
            httpx.Response(200, json=job_record("cancelled")))
    fake.on("POST", f"{JOB}/cancel", httpx.Response(202, json=job_record("running")))
    job = client.job(JOB_ID)
    assert job.cancel().record.status == "cancelled"


def test_preview_passes_frame_and_field_and_writes_the_file(fake, client, tmp_path):
    png = b"\x89PNG\r\n\x1a\n" + b"\0" * 32
    fake.on("GET", JOB, httpx.Response(200, json=job_record("succeeded")))
    fake.on("GET", f"{JOB}/preview.png", httpx.Response(200, content=png, headers={"content-type": "image/png"}))
    image = client.job(JOB_ID).preview(frame=3, field="von_mises", path=tmp_path / "p.png")
    assert image == png and (tmp_path / "p.png").read_bytes() == png
    params = fake.calls("GET", f"{JOB}/preview.png")[0].url.params
    assert (params["frame"], params["field"]) == ("3", "von_mises")


def test_animate_asks_for_the_format_of_the_suffix_and_writes_the_file(fake, client, tmp_path):
    gif, mp4 = b"GIF89a" + b"\0" * 16, b"\0\0\0\x18ftypmp42"
    fake.on("GET", JOB, httpx.Response(200, json=job_record("succeeded")))
    fake.on("GET", f"{JOB}/animation.gif", httpx.Response(200, content=gif))
    fake.on("GET", f"{JOB}/animation.mp4", httpx.Response(200, content=mp4))
    job = client.job(JOB_ID)
    assert job.animate(tmp_path / "run.gif", field="von_mises").read_bytes() == gif
    assert job.animate(tmp_path / "run.MP4").read_bytes() == mp4
    assert fake.calls("GET", f"{JOB}/animation.gif")[0].url.params["field"] == "von_mises"
    assert "field" not in fake.calls("GET", f"{JOB}/animation.mp4")[0].url.params
    with pytest.raises(ValueError, match="a .gif or an .mp4"):
        job.animate(tmp_path / "run.avi")
    assert not (tmp_path / "run.avi").exists()


def test_series_are_numpy_arrays(fake, client):
    np = pytest.importorskip("numpy")
    fake.on("GET", JOB, httpx.Response(200, json=job_record("succeeded")))
    fake.on("GET", f"{JOB}/series", httpx.Response(200, json={"time": [0.0, 0.1], "kinetic_energy": [1.0, None]}))
    series = client.job(JOB_ID).series()
    assert isinstance(series["time"], np.ndarray)
    np.testing.assert_array_equal(series["time"], [0.0, 0.1])
    assert np.isnan(series["kinetic_energy"][1])  # a null in JSON (a non-finite value) stays missing


# -- downloads -----------------------------------------------------------------------


class BrokenStream(httpx.SyncByteStream):
    """A body that breaks off after its first chunk, as a dropped connection does."""

    def __iter__(self):
        yield b"first half "
        raise httpx.ReadError("connection reset mid-body")


def test_download_retries_a_broken_transfer_from_scratch(fake, client, tmp_path):
    fake.on("GET", JOB, httpx.Response(200, json=job_record("succeeded")))
    fake.on("GET", f"{JOB}/result.h5", httpx.Response(200, stream=BrokenStream()),
            httpx.Response(200, content=b"the whole file"))
    path = client.job(JOB_ID).download(tmp_path / "result.h5")
    assert path.read_bytes() == b"the whole file"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["result.h5"]


def test_a_failed_download_leaves_no_half_written_file(fake, tmp_path):
    fake.on("GET", f"{JOB}/result.h5", httpx.Response(200, stream=BrokenStream()))
    target = tmp_path / "result.h5"
    target.write_bytes(b"an older download")
    with Client(BASE, retries=0, transport=httpx.MockTransport(fake)) as client:
        job = client._job(job_record("succeeded"))
        with pytest.raises(ServiceUnavailable, match="mid-body"):
            job.download(target)
    assert target.read_bytes() == b"an older download"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["result.h5"]


def test_download_before_the_result_exists_is_a_conflict(fake, client, tmp_path):
    fake.on("GET", f"{JOB}/result.h5", error(409, "no_result", "the job has no result yet"))
    with pytest.raises(Conflict, match="no result yet"):
        client._job(job_record("queued")).download(tmp_path / "r.h5")
    assert list(tmp_path.iterdir()) == []


# -- waiting -------------------------------------------------------------------------


def running(progress: float) -> httpx.Response:
    return httpx.Response(200, json=job_record("running", progress=progress, step=int(3500 * progress),
                                               sim_time=3.5 * progress, steps_per_second=812.0,
                                               eta_seconds=75.0))


def test_wait_returns_when_the_job_succeeds_and_shows_progress(fake, client, capsys):
    fake.on("GET", JOB, running(0.25), running(0.5), httpx.Response(200, json=job_record("succeeded", progress=1.0)))
    job = client._job(job_record())
    assert job.wait(poll=0.0) is job
    assert job.record.status == "succeeded"
    log = capsys.readouterr().err
    assert "25.0%" in log and "812 steps/s" in log and "ETA 1:15" in log and "succeeded" in log


def test_wait_raises_job_failed_with_the_solver_diagnostic(fake, client):
    diagnostic = "unstable at step 812: particle 17 has non-finite velocity"
    fake.on("GET", JOB, running(0.3), httpx.Response(200, json=job_record("failed", error=diagnostic)))
    with pytest.raises(JobFailed) as caught:
        client._job(job_record()).wait(poll=0.0, progress=False)
    assert caught.value.diagnostic == diagnostic and caught.value.status == "failed"
    assert diagnostic in str(caught.value)


def test_wait_on_a_cancelled_job_raises_job_cancelled(fake, client):
    fake.on("GET", JOB, httpx.Response(200, json=job_record("cancelled")))
    with pytest.raises(JobCancelled):
        client._job(job_record()).wait(progress=False)


def test_wait_gives_up_after_its_timeout(fake, client):
    fake.on("GET", JOB, running(0.1))
    with pytest.raises(WaitTimeout, match="still running"):
        client._job(job_record()).wait(timeout=0.2, poll=0.05, progress=False)
    assert len(fake.calls("GET", JOB)) >= 2


def test_progress_line_and_durations():
    record = JobRecord.model_validate(job_record("running", progress=0.5, sim_time=1.75,
                                                 steps_per_second=1234.0, eta_seconds=3725))
    line = format_progress(record, width=10)
    assert line.startswith("[#####-----]   50.0%")  # percent padded to a fixed width
    assert "t 1.75/3.5" in line and "1,234 steps/s" in line and "ETA 1:02:05" in line
    assert format_duration(None) == "?" and format_duration(59.6) == "1:00"


# -- the async twin ------------------------------------------------------------------


def test_async_client_has_the_same_surface(fake, async_client_factory, tmp_path):
    pages = {None: {"jobs": [job_record(id="a")], "next_cursor": "c1"},
             "c1": {"jobs": [job_record(id="b")], "next_cursor": None}}
    fake.on("GET", "/v1/jobs", lambda request: httpx.Response(200, json=pages[request.url.params.get("cursor")]))
    fake.on("POST", "/v1/jobs", httpx.Response(202, json=job_record()))
    fake.on("GET", JOB, error(503, "unavailable", "busy"), running(0.5),
            httpx.Response(200, json=job_record("succeeded")))
    fake.on("GET", f"{JOB}/result.h5", httpx.Response(200, content=b"hdf5 bytes"))
    fake.on("DELETE", JOB, httpx.Response(204))

    async def scenario() -> list[str]:
        async with async_client_factory() as client:
            ids = [job.id async for job in client.jobs()]
            job = await client.submit(SCENE)
            await job.wait(poll=0.0, progress=False)
            await job.download(tmp_path / "r.h5")
            await job.delete()
            return ids

    assert asyncio.run(scenario()) == ["a", "b"]
    assert (tmp_path / "r.h5").read_bytes() == b"hdf5 bytes"
    assert len(fake.calls("DELETE", JOB)) == 1


def test_async_errors_are_typed_the_same_way(fake, async_client_factory):
    details = [{"path": "time.end", "message": "must be > 0"}]
    fake.on("POST", "/v1/jobs", error(422, "validation_failed", "invalid", details))

    async def scenario() -> None:
        async with async_client_factory() as client:
            await client.submit(SCENE)

    with pytest.raises(ValidationFailed) as caught:
        asyncio.run(scenario())
    assert caught.value.errors == details


# -- packaging -----------------------------------------------------------------------


def test_importing_the_sdk_loads_neither_numpy_nor_the_server():
    code = ("import sys, mpm_client, mpm_client.cli; "
            "print(sorted(m for m in ('numpy', 'h5py', 'numba', 'solver', 'service', 'worker') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         cwd=Path(__file__).parent)
    assert out.stdout.strip() == "[]"
