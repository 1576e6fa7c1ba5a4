"""The webhook sender of a worker: a thread that delivers the deliveries queued in
Redis (core/webhooks.py) when they are due, one POST at a time with a short timeout,
and queues a failed one again with backoff, at most MAX_TRIES tries. It runs beside
the jobs, so a slow or dead receiver delays no job and no API request."""
from __future__ import annotations

import json
import logging
import threading
import urllib.error
import urllib.request
from typing import Any

import redis

from core import sweeps, webhooks
from core.models import now_iso
from core.settings import Settings
from core.store import WEBHOOKS, JobStore, sweep_key

log = logging.getLogger("mpm.worker")

# KEYS: queue. ARGV: now, in-flight deadline. Claims up to 10 due deliveries: their score
# becomes the deadline, so that one whose sender dies is tried again then.
_CLAIM = """
local due = redis.call('ZRANGEBYSCORE', KEYS[1], '-inf', ARGV[1], 'LIMIT', 0, 10)
for _, m in ipairs(due) do redis.call('ZADD', KEYS[1], ARGV[2], m) end
return due
"""


class _NoRedirect(urllib.request.HTTPRedirectHandler):
    """A receiver's redirect is not followed (it could point anywhere): the try fails."""

    def redirect_request(self, *args: Any) -> None:
        return None


_opener = urllib.request.build_opener(_NoRedirect)


def post(url: str, body: bytes, headers: dict[str, str]) -> str | None:
    """POST; None when the receiver answered 2xx, else why not."""
    request = urllib.request.Request(url, data=body, method="POST",
                                     headers={"Content-Type": "application/json", **headers})
    try:
        with _opener.open(request, timeout=webhooks.TIMEOUT_SECONDS) as answer:
            return None if 200 <= answer.status < 300 else f"HTTP {answer.status}"
    except urllib.error.HTTPError as exc:
        return f"HTTP {exc.code}"
    except (OSError, ValueError) as exc:
        return str(exc) or type(exc).__name__


class WebhookSender:
    def __init__(self, store: JobStore, settings: Settings, interval: float = 0.5):
        self.store, self.settings, self.interval = store, settings, interval
        self._claim = store.redis.register_script(_CLAIM)
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._loop, name="mpm-webhooks", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(timeout=webhooks.TIMEOUT_SECONDS + 1)

    def _loop(self) -> None:
        while not self._stop.is_set():
            try:
                now = webhooks.now()
                for item in self._claim(keys=[WEBHOOKS], args=[now, now + webhooks.IN_FLIGHT_SECONDS]):
                    self.deliver(item)
            except redis.RedisError as exc:
                log.warning("webhooks: redis unavailable: %s", exc)
            self._stop.wait(self.interval)

    def deliver(self, item: str) -> None:
        """One try of a claimed delivery; settles it (done, queued again, or given up)."""
        kind, ident, tries = webhooks.parse_member(item)
        found = self._payload(kind, ident, first=tries == 1)
        failure = None
        if found is not None:
            url, payload = found
            body = json.dumps(payload).encode()
            headers = {"X-MPM-Signature": webhooks.signature(body, self.settings.webhook_secret or ""),
                       "X-MPM-Event": f"{kind}.finished", "X-MPM-Delivery": f"{kind}-{ident}-{tries}"}
            try:
                webhooks.check_url(url, self.settings)
                failure = post(url, body, headers)
            except webhooks.WebhookUrlError as exc:
                failure, tries = f"not allowed any more: {exc}", webhooks.MAX_TRIES
        pipe = self.store.redis.pipeline()
        pipe.zrem(WEBHOOKS, item)
        if failure and tries < webhooks.MAX_TRIES:
            pipe.zadd(WEBHOOKS, {webhooks.member(kind, ident, tries + 1): webhooks.now() + webhooks.backoff(tries)})
        pipe.execute()
        if failure:
            log.warning("webhook try %d of %d failed: %s", tries, webhooks.MAX_TRIES, failure,
                        extra={"job_id" if kind == "job" else "sweep_id": ident})
        elif found is not None:
            log.info("webhook delivered", extra={"job_id" if kind == "job" else "sweep_id": ident})

    def _payload(self, kind: str, ident: str, first: bool) -> tuple[str, dict[str, Any]] | None:
        """(URL, body) of a delivery; None when there is nothing to send (the job or the
        sweep was deleted, has no callback, or the sweep still has jobs to run)."""
        if kind == "job":
            record = self.store.get(ident)
            return (record["callback_url"], record) if record and record.get("callback_url") else None
        sweep = self.store.get_sweep(ident)
        if not sweep or not sweep.get("callback_url"):
            return None
        shown = sweeps.view(self.store, sweep)
        if shown["status"] != "finished":
            return None
        if first and not self.store.redis.hsetnx(sweep_key(ident), "notified_at", json.dumps(now_iso())):
            return None  # another job's end queued it too: delivered once
        return sweep["callback_url"], shown
