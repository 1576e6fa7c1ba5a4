"""A worker's loops that run beside its jobs in a daemon thread of their own: the heartbeat
(worker/heartbeat.py) and the webhook sender (worker/webhooks.py)."""
from __future__ import annotations

import threading
from typing import Callable


class BackgroundLoop:
    """Runs ``loop`` in a daemon thread called ``name`` from :meth:`start`; the loop ends when
    ``self._stop`` is set, which :meth:`stop` does before waiting ``join_timeout`` seconds for it
    (a daemon thread: a loop stuck past that does not keep the worker's process alive)."""

    def __init__(self, loop: Callable[[], None], name: str, join_timeout: float) -> None:
        self._stop = threading.Event()
        self._thread = threading.Thread(target=loop, name=name, daemon=True)
        self._join_timeout = join_timeout

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=self._join_timeout)
