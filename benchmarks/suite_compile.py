"""Where a cold run of the test suite spends its compile time: numba's compile events, per test.

    rm -rf /tmp/suite-cache
    MPM_CACHE_DIR=/tmp/suite-cache SUITE_COMPILE_OUT=/tmp/census.jsonl \\
        python3 scripts/dev.py test -p benchmarks.suite_compile   # the suite, on an empty kernel cache
    python benchmarks/suite_compile.py /tmp/census.jsonl    # the tables

As a pytest plugin (`-p benchmarks.suite_compile`, imported from the repository's root: with
benchmarks/ itself on the path, benchmarks/service.py would hide the service package from the
suite's `mpm serve`), each test process appends
to SUITE_COMPILE_OUT one line per compilation numba made in it (the kernel, its argument
types, the test that caused it, its seconds) and one per test (its start and end). numba raises its `numba:compile`
event only on a cache miss, after the kernel cache's compile lock (solver/kernel_cache.py): a
process that waits for another's compilation and loads the result counts nothing. The seconds
are wall time in the worker: under four workers on two cores about twice the CPU time. What
subprocesses compile (`mpm run -n 2`, the service's workers) is not seen.

The tables: compile seconds by kind (a parallel form, its serial twin `<name>__one_thread`,
or a kernel without a twin), by test file, and by module (a generated fused module is named
by its variant), and the tests' wall time by file.
"""
from __future__ import annotations

import collections
import json
import os
import sys
import time

import pytest

_records: list[dict] = []
_running = {"test": None}


def pytest_configure(config):
    from numba.core import event

    class _Compilations(event.Listener):
        """The outermost compilation of each nest (a kernel compiles its callees inside its own)."""

        def __init__(self):
            self.started = []

        def on_start(self, ev):
            self.started.append(time.perf_counter())

        def on_end(self, ev):
            start = self.started.pop()
            if self.started:
                return
            function = getattr(ev.data.get("dispatcher"), "py_func", None)
            name = f"{getattr(function, '__module__', '?')}.{getattr(function, '__qualname__', '?')}"
            _records.append({"test": _running["test"], "kernel": name, "signature": str(ev.data.get("args")),
                             "seconds": time.perf_counter() - start})

    event.register("numba:compile", _Compilations())


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    _running["test"] = item.nodeid
    start = time.time()
    yield
    _records.append({"test": item.nodeid, "start": start, "end": time.time()})
    _running["test"] = None


def pytest_unconfigure(config):
    worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
    with open(os.environ.get("SUITE_COMPILE_OUT", "suite_compile.jsonl"), "a") as out:
        for record in _records:
            out.write(json.dumps({**record, "worker": worker}) + "\n")


def _kind(kernel: str, twinned: set[str]) -> str:
    if kernel.endswith("__one_thread"):
        return "serial twins"
    return "parallel forms" if kernel in twinned else "no twin"


def _module(kernel: str) -> str:
    module = kernel.rsplit(".", 1)[0]
    return module.rsplit(".", 1)[-1] if "._generated." in module else module


def _table(title: str, totals: collections.Counter, rows: int) -> None:
    print(f"\n| {title} | seconds |\n|---|---|")
    for name, seconds in totals.most_common(rows):
        print(f"| {name} | {seconds:.0f} |")


def summarise(path: str, rows: int = 15) -> None:
    records = [json.loads(line) for line in open(path)]
    compiled = [r for r in records if "kernel" in r]
    tests = [r for r in records if "start" in r]
    twinned = {r["kernel"][:-len("__one_thread")] for r in compiled if r["kernel"].endswith("__one_thread")}
    kinds, files, modules, walls = (collections.Counter() for _ in range(4))
    for r in compiled:
        kinds[_kind(r["kernel"], twinned)] += r["seconds"]
        files[(r["test"] or "(outside a test)").split("::")[0]] += r["seconds"]
        modules[_module(r["kernel"])] += r["seconds"]
    for r in tests:
        walls[r["test"].split("::")[0]] += r["end"] - r["start"]
    print(f"{len(compiled)} compilations, {sum(kinds.values()):.0f} s; {len(tests)} tests, "
          f"{sum(walls.values()):.0f} s of test time over {len({r['worker'] for r in tests})} processes")
    seen = collections.Counter((r["kernel"], r.get("signature")) for r in compiled)
    print(f"{sum(n - 1 for n in seen.values())} of them a kernel and signature compiled before in the suite "
          "(by another worker: each process compiles a signature at most once)")
    _table("kind", kinds, rows)
    _table("test file (compiling)", files, rows)
    _table("module", modules, rows)
    _table("test file (wall)", walls, rows)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    summarise(sys.argv[1])
