"""The worker's warm-up (worker/warmup.py): only the variants not yet compiled, flagged while it runs."""
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from worker import warmup


def test_a_warm_cache_starts_no_process_and_flags_nothing(monkeypatch):
    monkeypatch.setattr(warmup, "pending", lambda threads: [])
    monkeypatch.setattr(warmup, "_compile", lambda *a: (_ for _ in ()).throw(AssertionError("compiled")))
    flags = []
    warmup.warm_up(warming=flags.append)
    assert flags == []


def test_each_pending_variant_compiles_once_while_flagged(monkeypatch):
    flags, compiled = [], []
    monkeypatch.setattr(warmup, "pending", lambda threads: [(2, "linear_elastic", 1), (3, "neo_hookean", 2)])
    monkeypatch.setattr(warmup, "_compile",
                        lambda dim, model, threads, folder, timeout: compiled.append((dim, model, threads, flags[:])))
    warmup.warm_up(warming=flags.append, workers=2)
    assert sorted(compiled) == [(2, "linear_elastic", 1, [True]), (3, "neo_hookean", 2, [True])]
    assert flags == [True, False]


def test_pending_leaves_out_the_variants_a_run_marked_compiled(monkeypatch):
    from solver import cost

    monkeypatch.setattr(cost, "is_compiled", lambda scene, threads: scene.dimension == 1 or threads == 1)
    assert warmup.pending(threads=(1, 2)) == [(dim, model, 2) for dim, model in warmup.WARMUP if dim != 1]


def test_the_warm_up_compiles_the_parallel_forms_only_for_jobs_that_may_take_several_cores():
    assert warmup.thread_counts(1) == (1,)
    assert warmup.thread_counts(4) == (1, 4)



def _running(pid: int) -> bool:
    """Whether a process exists and has not ended (a zombie waits to be collected: ended)."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def test_a_worker_killed_while_it_warms_up_leaves_no_compile_running(tmp_path):
    """A process warming up killed with SIGKILL, as a crashed worker is: its compile ends with
    it. The stand-in compile runs a minute and, as the solver does while it compiles (it stops
    at its next step), takes no notice of SIGTERM; the real ones compiled on into the cache
    folder of a service already stopped."""
    ready = tmp_path / "ignoring"
    stand_in = [sys.executable, "-c", "import signal, time; signal.signal(signal.SIGTERM, signal.SIG_IGN); "
                f"open({str(ready)!r}, 'w').close(); time.sleep(60)"]
    program = ("from pathlib import Path; from worker import warmup; "
               f"warmup.solver_command = lambda *a, **k: {stand_in!r}; "
               f"warmup._compile(2, 'linear_elastic', 1, Path({str(tmp_path)!r}), 600)")
    worker = subprocess.Popen([sys.executable, "-c", program], cwd=Path(warmup.__file__).parents[1])
    children = Path(f"/proc/{worker.pid}/task/{worker.pid}/children")
    deadline = time.monotonic() + 30
    while not ready.exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    compile_pid = int(children.read_text().split()[0])
    os.kill(worker.pid, signal.SIGKILL)
    worker.wait()
    deadline = time.monotonic() + 10
    while _running(compile_pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not _running(compile_pid)
