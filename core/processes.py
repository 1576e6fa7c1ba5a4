"""Child processes that end with their parent: the worker's solver, `mpm serve`'s
worker and embedded Redis."""
from __future__ import annotations

import signal
import sys


def die_with_parent() -> None:
    """For `preexec_fn` (Linux): the child gets SIGTERM when the thread that started it
    dies, so that a killed worker (or `mpm serve`) leaves no solver (or Redis) behind."""
    if sys.platform.startswith("linux"):
        import ctypes
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG
