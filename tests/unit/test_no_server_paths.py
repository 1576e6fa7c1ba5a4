"""No server path reaches a client (issue 49): the solver's last line goes to the job's log
(GET /v1/jobs/{id}/log, `mpm log`, the dashboard) without result_path's folder or out_dir,
and what the API reads from a job's folder is shown with `<job>` and `<data>` for its paths."""
import io
import json
import queue

from core.paths import JobFiles
from worker.runner import _read_lines

JOB = "0b7d5e1c-2a8e-4a55-9d0f-7c1f3b8f6e21"


def test_the_solvers_last_line_is_logged_without_the_servers_paths(tmp_path):
    folder = tmp_path / "data" / "jobs" / JOB
    done = {"event": "done", "status": "complete", "steps": 10, "result_path": str(folder / "result.h5"),
            "out_dir": str(folder)}
    lines, log = queue.Queue(), io.StringIO()
    _read_lines(io.StringIO(json.dumps({"event": "progress", "step": 1}) + "\n" + json.dumps(done) + "\n"), lines, log)
    logged = log.getvalue()
    assert str(tmp_path) not in logged
    assert json.loads(logged) == {"event": "done", "status": "complete", "steps": 10, "result_path": "result.h5"}
    assert lines.get()["step"] == 1 and lines.get() == done   # the worker still reads the whole line


def test_a_jobs_paths_are_redacted(tmp_path):
    files = JobFiles(tmp_path / "data" / "jobs", JOB)
    text = (f'{{"result_path": "{files.result}"}} OSError: unable to open {files.dir}/checkpoint.h5; '
            f"redis at {tmp_path / 'data' / 'redis'}")
    shown = files.redact(text)
    assert str(tmp_path) not in shown
    assert shown == '{"result_path": "<job>/result.h5"} OSError: unable to open <job>/checkpoint.h5; redis at <data>/redis'
