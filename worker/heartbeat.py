"""A worker's heartbeat in Redis (`/readyz` counts the workers seen recently), the
recovery of jobs whose worker died: their lease expires, and a live worker puts
them back on the queue (instead of waiting for the broker's visibility timeout),
and the periodic removal of results past their retention period."""
from __future__ import annotations

import logging
import time
from typing import Callable

import redis

from core.store import HEARTBEAT_INTERVAL, JobStore
from worker.background import BackgroundLoop

log = logging.getLogger("mpm.worker")


class Heartbeat(BackgroundLoop):
    def __init__(self, store: JobStore, worker: str, enqueue: Callable[[str], None],
                 sweep_every: float, retain: Callable[[], object] | None = None,
                 retain_every: float = 3600.0):
        self.store, self.worker, self.enqueue = store, worker, enqueue
        self.sweep_every = sweep_every
        self.retain, self.retain_every = retain, retain_every
        super().__init__(self._beat, "mpm-heartbeat", join_timeout=HEARTBEAT_INTERVAL + 1)

    def stop(self) -> None:
        super().stop()
        try:
            self.store.worker_gone(self.worker)
        except redis.RedisError:
            pass

    def _beat(self) -> None:
        next_sweep = next_retention = 0.0
        while not self._stop.is_set():
            try:
                self.store.heartbeat(self.worker)
                if time.monotonic() >= next_sweep:
                    next_sweep = time.monotonic() + self.sweep_every
                    for job_id in self.store.requeue_orphans():
                        log.warning("job requeued: its worker was lost",
                                    extra={"job_id": job_id, "worker": self.worker})
                        self.enqueue(job_id)
                if self.retain is not None and time.monotonic() >= next_retention:
                    next_retention = time.monotonic() + self.retain_every
                    self.retain()
            except redis.RedisError as exc:
                log.warning("heartbeat failed: %s", exc, extra={"worker": self.worker})
            self._stop.wait(HEARTBEAT_INTERVAL)
