"""numba's `njit` and `prange` for the solver's kernels, with the solver's kernel cache
installed first (solver/kernel_cache.py says why): every module that defines a kernel
imports them from here, so no kernel's cache is set up before the cache is.

A parallel kernel (`njit(parallel=True)`) comes in two forms from one source
(`ThreadedKernel`): numba's parallel form, and a serial twin in which `prange` is `range`,
run while this thread's solver runs on one thread (`use_threads`, set by
solver/threads.py), and by a kernel called outside a run in a process that has one core
(MPM_CORES=1, as a worker's share or a test worker's). The twin compiles in about 0.6 of
the time (two_disks: 9.5 s against 16.7 s; docs/internals.md), and gives the same bits, since
the parallel form on one thread runs the same blocks in the same order. So a run on one
thread (a small scene, an MPI rank sharing the cores, a test worker) never waits on numba's
parallel compiler; each form is compiled only when first called.
"""
from __future__ import annotations

import threading
from types import FunctionType

from numba import njit as _numba_njit
from numba import prange

from solver import kernel_cache
from solver.thread_count import available_cores

kernel_cache.install()

__all__ = ["njit", "prange", "ThreadedKernel", "use_threads"]

_runs = threading.local()   # numba's thread count is per Python thread too (numba.set_num_threads)
_ONE_CORE = available_cores() == 1   # read once: the process's share of the cores is fixed


def use_threads(count: int | None) -> None:
    """The thread count this Python thread's kernels run on: one runs the serial twins; None,
    what a thread that never set it runs (the twins where the process has one core)."""
    _runs.one_thread = _ONE_CORE if count is None else count == 1


def _as_a_loop_body(flags):
    """The flags numba compiles a parallel loop's body with (numba/parfors/parfor_lowering.py):
    numpy's error model (a division by zero gives inf, it does not raise) and, where its alias
    analysis finds no two of the body's arrays to be the same memory, LLVM's noalias on them.
    A twin's loops without them ran the 2D MLS blocks of benchmarks/throughput.py 1.3-1.45x
    slower than the parallel form on one thread (LLVM kept them scalar); with them, as fast.
    The body's arrays are the kernel's own arguments, so the twin assumes what the parallel
    form does: that no two of them share memory."""
    flags.error_model = "numpy"
    flags.noalias = True
    return flags


class _SerialGlobals(dict):
    """A serial twin's globals: its module's, with every ThreadedKernel read as its serial
    twin, so that a twin calling another kernel calls that kernel's twin. Empty itself, it
    reads the module's names when they are looked up (numba does so when it compiles), so
    names defined after the kernel are seen too."""

    def __init__(self, module_globals: dict):
        super().__init__()
        self._module = module_globals

    def __missing__(self, name):
        value = self._module[name]
        return value.serial if isinstance(value, ThreadedKernel) else value


class ThreadedKernel:
    """A parallel kernel's two compiled forms, called as one function."""

    def __init__(self, function: FunctionType, options: dict):
        self.parallel = _numba_njit(**options)(function)
        twin = FunctionType(function.__code__, _SerialGlobals(function.__globals__), function.__name__,
                            function.__defaults__, function.__closure__)
        # Its own entry in the kernel cache: numba names an entry by the function's
        # qualified name and does not key it by the options it was compiled with.
        twin.__qualname__ = f"{function.__qualname__}__one_thread"
        twin.__module__, twin.__doc__ = function.__module__, function.__doc__
        self.serial = _numba_njit(**{**options, "parallel": False})(twin)
        if options.get("parallel"):
            self.serial._compiler._customize_flags = _as_a_loop_body
        self.__name__, self.__qualname__ = function.__name__, function.__qualname__
        self.__doc__, self.__module__, self.__wrapped__ = function.__doc__, function.__module__, function

    @property
    def _numba_type_(self):
        """What numba sees where another kernel calls this one: the parallel form (a serial
        twin's calls resolve to the twins instead, through `_SerialGlobals`)."""
        from numba.core import types
        return types.Dispatcher(self.parallel)

    def __call__(self, *args):
        return (self.serial if getattr(_runs, "one_thread", _ONE_CORE) else self.parallel)(*args)


def _loop_body(function: FunctionType, options: dict):
    """numba's dispatcher of a function compiled as the body of a parallel loop (`_as_a_loop_body`)."""
    dispatcher = _numba_njit(**options)(function)
    dispatcher._compiler._customize_flags = _as_a_loop_body
    return dispatcher


def njit(*args, twin: bool = False, loop_body: bool = False, **options):
    """numba's njit; with `parallel=True`, a ThreadedKernel. `twin=True` makes a ThreadedKernel
    of a function with no parallel loop of its own that calls parallel kernels, so that its
    twin calls theirs (both its forms compile without numba's parallel passes). `loop_body=True`
    compiles a function that a parallel kernel's loop calls as that loop's body would be
    (`_as_a_loop_body`): no two of its arrays may share memory."""
    if not (options.get("parallel") or twin or loop_body):
        return _numba_njit(*args, **options)
    if args:
        raise TypeError("njit(parallel=True), njit(twin=True) and njit(loop_body=True) take options only, "
                        "as decorator factories")
    if loop_body:
        return lambda function: _loop_body(function, options)
    return lambda function: ThreadedKernel(function, options)
