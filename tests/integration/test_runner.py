"""The solver runner's process handling, with small child programs standing in for the
solver's command line (its output protocol: JSON lines on stdout, the last one `done`)."""
from __future__ import annotations

import os
import sys
import textwrap
import time

from worker.runner import run_solver

CHILD = textwrap.dedent("""
    import json, signal, sys, time
    stop = False
    def on_term(*_):
        global stop
        stop = True
    signal.signal(signal.SIGTERM, on_term if sys.argv[1] == "polite" else signal.SIG_IGN)
    print("not json, goes to the log", flush=True)
    print("a warning", file=sys.stderr, flush=True)
    for step in range(int(sys.argv[2])):
        if stop:
            print(json.dumps({"event": "done", "status": "partial", "reason": "cancelled",
                              "steps": step}), flush=True)
            sys.exit(3)
        print(json.dumps({"event": "progress", "step": step, "fraction": step / 100}), flush=True)
        time.sleep(0.01)
    print(json.dumps({"event": "done", "status": "complete", "reason": "finished", "steps": step + 1}))
""")


def _child(tmp_path, mode: str, steps: int) -> list[str]:
    script = tmp_path / "child.py"
    script.write_text(CHILD)
    return [sys.executable, str(script), mode, str(steps)]


def test_progress_is_forwarded_at_a_bounded_rate(tmp_path):
    seen = []
    started = time.monotonic()
    outcome = run_solver(_child(tmp_path, "polite", 100), tmp_path / "solver.log",
                         on_progress=seen.append, should_stop=lambda: None, progress_interval=0.2)
    elapsed = time.monotonic() - started
    assert outcome.returncode == 0 and outcome.stopped is None
    assert outcome.done["status"] == "complete" and outcome.done["steps"] == 100
    # 100 lines over >= 1 s: at most one per 0.2 s gets through, plus the final one
    assert 2 <= len(seen) <= elapsed / 0.2 + 2
    assert seen[-1]["step"] == 99  # the latest line always arrives
    log = (tmp_path / "solver.log").read_text()
    assert "a warning" in log and "not json" in log
    assert "a warning" in outcome.log_tail


def test_stop_sends_sigterm_and_the_child_ends_partial(tmp_path):
    calls = []

    def should_stop():
        calls.append(time.monotonic())
        return "cancelled" if len(calls) > 2 else None

    outcome = run_solver(_child(tmp_path, "polite", 100000), tmp_path / "solver.log",
                         on_progress=lambda _: None, should_stop=should_stop, poll_interval=0.1)
    assert outcome.stopped == "cancelled"
    assert outcome.returncode == 3 and outcome.done["reason"] == "cancelled"


def test_a_child_ignoring_sigterm_is_killed_after_the_grace_period(tmp_path):
    started = time.monotonic()
    seen = []  # stop once the child runs (its SIGTERM handler is in place), not before
    outcome = run_solver(_child(tmp_path, "stubborn", 100000), tmp_path / "solver.log",
                         on_progress=seen.append, should_stop=lambda: "cancelled" if seen else None,
                         poll_interval=0.05, grace_seconds=0.5)
    assert outcome.stopped == "cancelled" and outcome.returncode == -9
    assert outcome.done is None
    assert time.monotonic() - started < 5


def test_the_whole_process_group_is_stopped(tmp_path):
    """A grandchild (as under mpiexec) is stopped with the child."""
    pid_file = tmp_path / "grandchild.pid"
    script = tmp_path / "parent.py"
    script.write_text(textwrap.dedent(f"""
        import subprocess, sys, time
        child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
        open({str(pid_file)!r}, "w").write(str(child.pid))
        child.wait()
    """))
    outcome = run_solver([sys.executable, str(script)], tmp_path / "solver.log",
                         on_progress=lambda _: None,
                         should_stop=lambda: "cancelled" if pid_file.exists() else None,
                         poll_interval=0.05, grace_seconds=1)
    assert outcome.stopped == "cancelled"
    grandchild = int(pid_file.read_text())
    deadline = time.monotonic() + 3
    while time.monotonic() < deadline:
        try:
            os.kill(grandchild, 0)
        except ProcessLookupError:
            break
        time.sleep(0.05)
    else:
        raise AssertionError("the grandchild outlived the stop")


def test_timeout_stops_the_child(tmp_path):
    outcome = run_solver(_child(tmp_path, "polite", 100000), tmp_path / "solver.log",
                         on_progress=lambda _: None, should_stop=lambda: None,
                         poll_interval=0.05, timeout_seconds=0.5)
    assert outcome.stopped == "timeout" and outcome.returncode == 3
