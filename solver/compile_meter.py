"""Counting numba's compilations in this process: `with CompileMeter() as meter: ...`."""
from __future__ import annotations

import time

from numba.core import event as numba_event

from solver.kernel_cache import is_solver_kernel


class CompileMeter(numba_event.Listener):
    """Counts the solver's kernels numba compiles (cache misses: a kernel loaded from the
    cache is not one; numba's own functions compiled inside a kernel are not counted) and
    the wall time spent compiling, outermost compilations only; `with CompileMeter() as m:`."""

    def __init__(self) -> None:
        super().__init__()
        self.count = 0
        self.seconds = 0.0
        self._depth = 0
        self._started = 0.0

    def on_start(self, event) -> None:
        self.count += is_solver_kernel(event.data["dispatcher"])
        if self._depth == 0:
            self._started = time.perf_counter()
        self._depth += 1

    def on_end(self, event) -> None:
        self._depth -= 1
        if self._depth == 0:
            self.seconds += time.perf_counter() - self._started

    def __enter__(self) -> "CompileMeter":
        numba_event.register("numba:compile", self)
        return self

    def __exit__(self, *exc) -> None:
        numba_event.unregister("numba:compile", self)
