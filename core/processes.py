"""Child processes that end with their parent: the worker's solver, `mpm serve`'s
worker and embedded Redis."""
from __future__ import annotations

import signal
import sys


def die_with_parent(sig: int = signal.SIGTERM) -> None:
    """For `preexec_fn` (Linux): the child gets `sig` when the thread that started it
    dies, so that a killed worker (or `mpm serve`) leaves no solver (or Redis) behind."""
    if sys.platform.startswith("linux"):
        import ctypes
        ctypes.CDLL("libc.so.6", use_errno=True).prctl(1, sig)  # PR_SET_PDEATHSIG


def killed_with_parent() -> None:
    """`die_with_parent` with SIGKILL: for a child with nothing to save. A solver run takes
    SIGTERM as a request to stop at its next step, which comes only after it has compiled."""
    die_with_parent(signal.SIGKILL)
