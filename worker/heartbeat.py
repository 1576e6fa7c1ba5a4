"""A worker's heartbeat in Redis: `/readyz` counts the workers seen recently."""
from __future__ import annotations

import logging
import threading

import redis

from worker.store import JobStore

log = logging.getLogger("mpm.worker")

INTERVAL = 2.0
# A worker not heard from for this long is taken as gone.
MAX_AGE = 10.0


class Heartbeat:
    def __init__(self, store: JobStore, worker: str):
        self.store, self.worker = store, worker
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._beat, name="mpm-heartbeat", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=INTERVAL + 1)
        try:
            self.store.worker_gone(self.worker)
        except redis.RedisError:
            pass

    def _beat(self) -> None:
        while not self._stop.is_set():
            try:
                self.store.heartbeat(self.worker)
            except redis.RedisError as exc:
                log.warning("heartbeat failed: %s", exc, extra={"worker": self.worker})
            self._stop.wait(INTERVAL)
