"""Compiling a new variant from both ends: a helper process beside a cold run.

numba compiles a kernel when it is first called, so a run compiles its step's kernels
one after another in the order the scheme calls them, on one core. When the run's
variant is not in the kernel cache and a core is idle, `start` launches this module as
a second process on a coarse copy of the scene (one particle per cell: the same kernel
signatures) that calls the phases after the weights in reverse order, and then the step
hooks, so the two processes compile from both ends and each loads from the shared cache
what the other saved first (solver/kernel_cache.py: saves of processes at once are
safe). The helper only compiles: what its kernels compute on a state they were not
meant for is thrown away (a phase that fails is skipped), and the run stops it after its
own first step. `MPM_PRECOMPILE=0` turns it off (the test suite does, but for its own test).
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time

from solver import cost
from solver.thread_count import available_cores

# A core counts as free when at least this much of one sat idle over IDLE_WINDOW seconds just
# now. Not the load average: it trails by a minute, so a run started right after another one
# (a compile is a core busy for tens of seconds) saw no free core and compiled alone.
IDLE_CORE = 0.75
IDLE_WINDOW = 0.2


def wanted(scene, threads: int) -> bool:
    """A cold, single-process run on a machine with a core to spare."""
    if os.environ.get("MPM_PRECOMPILE", "1") == "0" or scene.parallel.processes > 1:
        return False
    if available_cores() < 2 or cost.is_compiled(scene, threads):
        return False
    return idle_cores() >= IDLE_CORE


def idle_cores() -> float:
    """How many cores sat idle over the last IDLE_WINDOW seconds (Linux: /proc/stat's idle and
    iowait ticks of all cores), else the cores the load average leaves."""
    try:
        before = _cpu_ticks()
        time.sleep(IDLE_WINDOW)
        after = _cpu_ticks()
    except (OSError, ValueError, IndexError):
        return available_cores() - os.getloadavg()[0]
    idle, total = after[0] - before[0], after[1] - before[1]
    return (os.cpu_count() or 1) * idle / total if total > 0 else 0.0


def _cpu_ticks() -> tuple[int, int]:
    """(idle + iowait, all) ticks of the machine's cores since boot, from /proc/stat's first line."""
    with open("/proc/stat") as stat:
        ticks = [int(field) for field in stat.readline().split()[1:]]
    return ticks[3] + ticks[4], sum(ticks)


def coarse(document: dict, threads: int) -> dict:
    """The scene with one particle per cell in every body: fewer particles, the same kernels
    (on the run's thread count, which decides the kernels' forms: solver/jit.py)."""
    bodies = []
    for body in document["bodies"]:
        ppc = body.get("particles_per_cell")
        bodies.append({**body, "particles_per_cell": [1] * len(ppc) if isinstance(ppc, list) else 1}
                      if ppc is not None else body)
    return {**document, "bodies": bodies, "parallel": {**document.get("parallel", {}), "threads": threads}}


def start(scene, threads: int) -> subprocess.Popen | None:
    """The helper process for a run of `scene` on `threads` threads, or None when it is not
    wanted or cannot start."""
    if not wanted(scene, threads):
        return None
    try:
        with tempfile.NamedTemporaryFile("w", suffix=".json", prefix="mpm-precompile-", delete=False) as file:
            json.dump(coarse(scene.model_dump(mode="json", exclude_unset=True), threads), file)
        return subprocess.Popen([sys.executable, "-m", "solver.precompile", file.name],
                                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    except OSError:
        return None


def stop(helper: subprocess.Popen | None) -> None:
    """End the helper (its saves are whole files renamed into place: a kill loses none)."""
    if helper is not None and helper.poll() is None:
        helper.kill()
        helper.wait()


class _Recorder:
    """Stands for the backend while a scheme runs: records the phase calls, runs none."""

    def __init__(self, sim):
        self.sim = sim
        self.calls: list[tuple[str, tuple, dict]] = []

    def __getattr__(self, name):
        return lambda *args, **kwargs: self.calls.append((name, args, kwargs))


def compile_backwards(sim, dt: float) -> None:
    """Call the step's phases after the weights from last to first, then the step hooks."""
    recorder = _Recorder(sim)
    sim.scheme(recorder, dt)
    first, *rest = recorder.calls
    calls = [lambda: getattr(sim.phases, first[0])(*first[1], **first[2])]
    calls += [lambda call=call: getattr(sim.phases, call[0])(*call[1], **call[2]) for call in reversed(rest)]
    calls += [lambda hook=hook: hook(sim, dt) for hook in sim.hooks.end_step]
    calls += [lambda hook=hook: hook(sim, sim.time + dt) for hook in sim.hooks.begin_step]
    for call in calls:
        try:
            call()
        except Exception:   # the kernel compiled before it ran on this made-up state: enough
            continue


def main(path: str) -> int:
    from solver.scene_checks import load_scene
    # The run's simulation (runner.make_simulation), built here: the runner starts this
    # helper and would be imported back by it.
    from solver.stepper import ExplicitMPM

    try:
        # A mesh or points file is named by the absolute path the run resolved when it validated
        # the scene; read without a folder, a document naming a file is refused (the service's
        # rule), and the helper died on every such scene, leaving the run to compile alone.
        scene = load_scene(json.loads(open(path).read()), files=os.path.dirname(path))
    finally:
        os.unlink(path)
    sim = ExplicitMPM(scene)
    compile_backwards(sim, scene.time.dt or sim.stable_time_step(scene.time.cfl))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
