"""The client commands of ``mpm`` against the scripted fake API, and the loading of other packages' commands."""
from __future__ import annotations

import base64
import json

import httpx
import pytest

from mpm_client import Client, cli
from sdk_fakes import JOB_ID, error, job_record, sent_json

JOB = f"/v1/jobs/{JOB_ID}"


@pytest.fixture
def servers(fake, monkeypatch):
    """Route every client the commands make to the fake; record the server URL and token they got."""
    seen: list[tuple[str | None, str | None]] = []

    def make(server, token=None):
        seen.append((server, token))
        return Client(server or "http://mpm.test", token=token, backoff=0.0, transport=httpx.MockTransport(fake))

    monkeypatch.setattr(cli, "Client", make)
    return seen


def test_submit_download_waits_and_writes_the_result(fake, servers, tmp_path, capsys):
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps({"version": 1, "name": "two-disks"}))
    fake.on("POST", "/v1/jobs", httpx.Response(202, json=job_record()))
    fake.on("GET", JOB, httpx.Response(200, json=job_record("running", progress=0.5)),
            httpx.Response(200, json=job_record("succeeded", progress=1.0)))
    fake.on("GET", f"{JOB}/result.h5", httpx.Response(200, content=b"hdf5"))
    out = tmp_path / "out.h5"
    code = cli.main(["submit", str(scene), "--download", str(out), "--server", "http://elsewhere:9000",
                     "--token", "t0k", "-n", "2", "--nodes", "2"])
    assert code == 0
    assert capsys.readouterr().out.strip() == JOB_ID  # the id alone on stdout, for scripts
    assert out.read_bytes() == b"hdf5"
    assert servers == [("http://elsewhere:9000", "t0k")]
    sent = sent_json(fake.calls("POST", "/v1/jobs")[0])
    assert (sent["processes"], sent["nodes"]) == (2, 2)


def test_submit_prints_every_validation_error_and_fails(fake, servers, tmp_path, capsys):
    scene = tmp_path / "scene.json"
    scene.write_text("{}")
    fake.on("POST", "/v1/jobs", error(422, "validation_failed", "the scene is invalid",
                                      [{"path": "time.end", "message": "must be > 0"},
                                       {"path": "bodies[0].material", "message": "no material 'steel'"}]))
    assert cli.main(["submit", str(scene)]) == 1
    err = capsys.readouterr().err
    assert "time.end: must be > 0" in err and "bodies[0].material: no material 'steel'" in err


def test_submit_wait_reports_a_failed_job(fake, servers, tmp_path, capsys):
    scene = tmp_path / "scene.json"
    scene.write_text("{}")
    fake.on("POST", "/v1/jobs", httpx.Response(202, json=job_record()))
    fake.on("GET", JOB, httpx.Response(200, json=job_record("failed", error="J <= 0 at particle 3")))
    assert cli.main(["submit", str(scene), "--wait", "-q"]) == 1
    assert "failed: J <= 0 at particle 3" in capsys.readouterr().err


def test_jobs_prints_a_table_newest_first(fake, servers, capsys):
    fake.on("GET", "/v1/jobs", httpx.Response(200, json={"jobs": [
        job_record("running", id="new", name="falling", progress=0.42),
        job_record("succeeded", id="old", name="two-disks", progress=1.0)], "next_cursor": None}))
    assert cli.main(["jobs", "--status", "running"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split() == ["ID", "NAME", "STATUS", "PROGRESS", "SIM", "TIME", "AGE"]
    assert lines[1].split()[:4] == ["new", "falling", "running", "42%"]
    assert lines[2].split()[:4] == ["old", "two-disks", "succeeded", "100%"]
    assert fake.requests[0].url.params["status"] == "running"


def test_jobs_limit_stops_after_that_many(fake, servers, capsys):
    fake.on("GET", "/v1/jobs", httpx.Response(200, json={
        "jobs": [job_record(id=str(i)) for i in range(3)], "next_cursor": "more"}))
    assert cli.main(["jobs", "--limit", "2", "--json"]) == 0
    assert [json.loads(line)["id"] for line in capsys.readouterr().out.splitlines()] == ["0", "1"]
    assert len(fake.requests) == 1


def test_status_cancel_and_download(fake, servers, tmp_path, capsys):
    fake.on("GET", JOB, httpx.Response(200, json=job_record("running", progress=0.5)),
            httpx.Response(200, json=job_record("running", progress=0.5)),
            httpx.Response(200, json=job_record("cancelled")))
    fake.on("POST", f"{JOB}/cancel", httpx.Response(202, json=job_record("running")))
    fake.on("GET", f"{JOB}/result.h5", httpx.Response(200, content=b"partial"))
    assert cli.main(["status", JOB_ID, "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["progress"] == 0.5
    assert cli.main(["cancel", JOB_ID]) == 0
    assert capsys.readouterr().out.strip() == f"{JOB_ID} cancelled"
    assert cli.main(["download", JOB_ID, str(tmp_path / "r.h5")]) == 0
    assert (tmp_path / "r.h5").read_bytes() == b"partial"


def test_an_unknown_job_is_an_error_naming_it(fake, servers, capsys):
    fake.on("GET", "/v1/jobs/nope", error(404, "not_found", "no job 'nope'"))
    assert cli.main(["status", "nope"]) == 1
    assert "mpm status: error: no job 'nope'" in capsys.readouterr().err


class FakeEntryPoint:
    def __init__(self, name: str, register=None, failure: Exception | None = None) -> None:
        self.name, self.value, self._register, self._failure = name, f"somewhere:{name}", register, failure

    def load(self):
        if self._failure:
            raise self._failure
        return self._register


def test_other_packages_commands_are_added_and_broken_ones_only_warned(monkeypatch, capsys):
    def register_run(subparsers):
        subparsers.add_parser("run").set_defaults(func=lambda args: 7)

    def register_submit_twice(subparsers):  # must be skipped: the client's submit is already there
        raise AssertionError("a command already present was registered again")

    monkeypatch.setattr(cli, "entry_points", lambda group: [
        FakeEntryPoint("run", register_run),
        FakeEntryPoint("submit", register_submit_twice),
        FakeEntryPoint("serve", failure=ImportError("No module named 'fastapi'")),
    ])
    assert cli.main(["run"]) == 7
    err = capsys.readouterr().err
    assert "warning: command 'serve'" in err and "No module named 'fastapi'" in err


def test_submit_inlines_a_mesh_file_beside_the_scene(fake, servers, tmp_path):
    """The service never opens a path named in a scene: `mpm submit` sends the mesh's bytes."""
    (tmp_path / "parts").mkdir()
    stl = b"solid part\nendsolid part\n" * 3
    (tmp_path / "parts" / "bracket.STL").write_bytes(stl)
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps({"bodies": [{"geometry": {"type": "union", "parts": [
        {"type": "mesh", "file": "parts/bracket.STL", "scale": 0.001}, {"type": "box"}]}}]}))
    fake.on("POST", "/v1/jobs", httpx.Response(202, json=job_record()))
    assert cli.main(["submit", str(scene)]) == 0
    sent = sent_json(fake.requests[-1])["scene"]["bodies"][0]["geometry"]["parts"]
    assert sent == [{"type": "mesh", "scale": 0.001, "format": "stl", "data": base64.b64encode(stl).decode()},
                    {"type": "box"}]


def test_submit_inlines_a_points_file_as_positions_and_volumes(fake, servers, tmp_path):
    (tmp_path / "cloud.csv").write_text("x,y,volume\n0.1,0.2,0.001\n0.3,0.4,0.002\n")
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps({"bodies": [{"geometry": {"type": "points", "file": "cloud.csv"}}]}))
    fake.on("POST", "/v1/jobs", httpx.Response(202, json=job_record()))
    assert cli.main(["submit", str(scene)]) == 0
    assert sent_json(fake.requests[-1])["scene"]["bodies"][0]["geometry"] == {
        "type": "points", "positions": [[0.1, 0.2], [0.3, 0.4]], "volumes": [0.001, 0.002]}

@pytest.mark.parametrize("command", [["submit"], ["sweep", "-p", "/time/dt=1,2"]], ids=["submit", "sweep"])
def test_a_scene_file_with_a_json_syntax_error_names_its_line_and_column(fake, servers, tmp_path, capsys, command):
    broken = tmp_path / "broken.json"
    broken.write_text('{"version": 1,\n  "name": }')  # the value is missing at line 2, column 11
    assert cli.main([command[0], str(broken), *command[1:]]) == 1
    assert f"{broken} is not valid JSON: line 2, column 11: Expecting value" in capsys.readouterr().err
    assert not fake.calls("POST", "/v1/jobs") and not fake.calls("POST", "/v1/sweeps")  # nothing was sent
