"""How the suite shares out over pytest-xdist workers (`scripts/dev.py test` starts them).

A file's tests stay together on one worker: many files set up a service stack, a browser
or a reference run once per module or session, and two workers would each pay for it.
The files in SPREAD hold no such fixture and spend their time compiling a kernel
specialised to each case, which is single-threaded; their tests go out one by one so
every core compiles. A run without workers (plain `pytest`, or no xdist) is not changed.

The grouping is a scheduler of its own rather than `--dist loadgroup` with marks:
xdist 3.8's loadgroup groups nothing under pytest 9.2 (it rewrites a test id pytest no
longer reads; pytest-dev/pytest-xdist#1386), and silently.
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest

# No precompiling helper beside cold runs (solver/precompile.py) but in its own test: whether
# it starts depends on the machine's load, and a test's outcome must not.
os.environ["MPM_PRECOMPILE"] = "0"
# The suite compiles the fused kernels without FMA contraction unless the environment says
# otherwise (`MPM_FMA=1 python3 scripts/dev.py test`): the regression cases need those, whose
# bits are the same on every CPU (tests/regression/snapshot.py), and every other test then
# loads the modules they compiled instead of compiling the contracted twin of each (most of a
# cold run is compiling). Runs contract by default; tests/unit/test_fused.py holds the
# contracted kernels to these to round-off, and sets MPM_FMA where a test is about it.
os.environ.setdefault("MPM_FMA", "0")
# Each worker's share of the cores, as a service worker gives each job its share (worker/tasks.py):
# a scene that names no thread count runs on one thread, in the kernels' serial twins, which
# compile in about a third of the parallel forms' time (solver/jit.py); the tests about threads
# name their counts and compile the parallel forms.
# The share is set here when the command line did not set MPM_CORES. pytest-xdist's controller
# imports this file before it starts its workers, which inherit its environment: the flag tells a
# worker that the MPM_CORES it sees is the controller's whole-machine figure, to divide again
# (without it, every worker ran a large scene on all the cores and compiled the parallel forms).
_SHARED_BY_THE_SUITE = "MPM_TEST_CORES_SHARED"
if "MPM_CORES" not in os.environ or os.environ.get(_SHARED_BY_THE_SUITE) == "1":
    from solver.thread_count import available_cores

    cores = available_cores({})   # this process's CPUs, not an inherited MPM_CORES
    os.environ["MPM_CORES"] = str(max(1, cores // int(os.environ.get("PYTEST_XDIST_WORKER_COUNT", "1"))))
    os.environ[_SHARED_BY_THE_SUITE] = "1"


@pytest.fixture(autouse=True)
def _kernels_in_the_workers_form():
    """Each test starts with the kernels' default form (solver/jit.py `use_threads(None)`: the serial
    twins on a worker's one core), so that a run on two threads earlier in this worker does not put
    a later test's direct kernel calls on the parallel forms, which compile three times as long."""
    jit = sys.modules.get("solver.jit")
    if jit is not None:
        jit.use_threads(None)


SPREAD = {"unit/test_fused.py", "regression/test_regression.py"}


@pytest.hookimpl(optionalhook=True)  # an xdist hook: pytest without xdist would refuse the name
def pytest_xdist_make_scheduler(config: pytest.Config, log):
    if config.getvalue("dist") != "load":  # a --dist the command line chose is left to xdist
        return None
    from xdist.scheduler import LoadScopeScheduling

    tests = Path(__file__).resolve().parent.relative_to(config.rootpath).as_posix()
    spread = {f"{tests}/{name}" for name in SPREAD}

    class FileScheduling(LoadScopeScheduling):
        """A work unit is a file, but for the SPREAD files, where it is a test."""

        def _split_scope(self, nodeid: str) -> str:
            path = nodeid.split("::", 1)[0]
            return nodeid if path in spread else path

    return FileScheduling(config, log)
