"""The webhook sender of a worker: a thread that delivers the deliveries queued in
Redis (core/webhooks.py) when they are due, one POST at a time with a short timeout,
and queues a failed one again with backoff, at most MAX_TRIES tries. It runs beside
the jobs, so a slow or dead receiver delays no job and no API request."""
from __future__ import annotations

import http.client
import json
import logging
import socket
import ssl
from typing import Any
from urllib.parse import urlsplit

import redis

from core import sweeps, webhooks
from core.models import now_iso
from core.settings import Settings
from core.store import WEBHOOKS, JobStore, sweep_key
from worker.background import BackgroundLoop

log = logging.getLogger("mpm.worker")

# KEYS: queue. ARGV: now, in-flight deadline. Claims up to 10 due deliveries: their score
# becomes the deadline, so that one whose sender dies is tried again then.
_CLAIM = """
local due = redis.call('ZRANGEBYSCORE', KEYS[1], '-inf', ARGV[1], 'LIMIT', 0, 10)
for _, m in ipairs(due) do redis.call('ZADD', KEYS[1], ARGV[2], m) end
return due
"""


class _PinnedHTTP(http.client.HTTPConnection):
    """Connects to the address the URL check resolved, not to the name again."""

    def __init__(self, host: str, address: str, **kwargs: Any):
        super().__init__(host, **kwargs)
        self._address = address

    def connect(self) -> None:
        self.sock = socket.create_connection((self._address, self.port), self.timeout)


class _PinnedHTTPS(http.client.HTTPSConnection):
    """TLS to the checked address; the certificate is still verified against the URL's name."""

    def __init__(self, host: str, address: str, **kwargs: Any):
        super().__init__(host, context=ssl.create_default_context(), **kwargs)
        self._address = address

    def connect(self) -> None:
        sock = socket.create_connection((self._address, self.port), self.timeout)
        self.sock = self._context.wrap_socket(sock, server_hostname=self.host)


def post(url: str, body: bytes, headers: dict[str, str], settings: Settings) -> str | None:
    """POST to the address the allow-list check resolved (no second lookup); None when the
    receiver answered 2xx, else why not. A redirect is not followed (it could point
    anywhere): the try fails. Raises webhooks.WebhookUrlError when the URL is not allowed."""
    host, port, address = webhooks.checked_target(url, settings)
    parts = urlsplit(url)
    kind = _PinnedHTTPS if parts.scheme == "https" else _PinnedHTTP
    connection = kind(host, str(address), port=port, timeout=webhooks.TIMEOUT_SECONDS)
    target = (parts.path or "/") + (f"?{parts.query}" if parts.query else "")
    try:
        connection.request("POST", target, body=body,
                           headers={"Content-Type": "application/json", **headers})
        status = connection.getresponse().status
        return None if 200 <= status < 300 else f"HTTP {status}"
    except (OSError, http.client.HTTPException, ValueError) as exc:
        return str(exc) or type(exc).__name__
    finally:
        connection.close()


class WebhookSender(BackgroundLoop):
    def __init__(self, store: JobStore, settings: Settings, interval: float = 0.5):
        self.store, self.settings, self.interval = store, settings, interval
        self._claim = store.redis.register_script(_CLAIM)
        super().__init__(self._loop, "mpm-webhooks", join_timeout=webhooks.TIMEOUT_SECONDS + 1)

    def _loop(self) -> None:
        while not self._stop.is_set():
            try:
                now = webhooks.now()
                claimed = self._claim(keys=[WEBHOOKS], args=[now, now + webhooks.IN_FLIGHT_SECONDS])
            except redis.RedisError as exc:
                log.warning("webhooks: redis unavailable: %s", exc)
                claimed = []
            for item in claimed:
                self._deliver_safely(item)
            self._stop.wait(self.interval)

    def _deliver_safely(self, item: str) -> None:
        """One delivery, whatever it raises: logged and settled (given up), never the thread's
        end, so no URL, answer or bug stops the deliveries after it."""
        try:
            self.deliver(item)
        except Exception as exc:   # noqa: BLE001 - the loop must outlive any one delivery
            log.exception("webhook delivery %s failed: %s", item, exc)
            try:
                self.store.redis.zrem(WEBHOOKS, item)   # not tried again: it would fail the same way
            except redis.RedisError:
                pass   # claimed until IN_FLIGHT_SECONDS: tried again then

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
                failure = post(url, body, headers, self.settings)
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
