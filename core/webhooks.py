"""Webhooks: when a job with a `callback_url` ends (or the last job of a sweep with
one), its final record is POSTed there, signed `X-MPM-Signature: sha256=<HMAC-SHA256
of the body with MPM_WEBHOOK_SECRET>`.

A delivery is queued in Redis by the same script that finishes the job (core/store.py),
so every way a job ends notifies once; the workers' sender threads (worker/webhooks.py)
deliver it, never a task or a request: a slow receiver blocks nobody. A failed try is
retried with backoff (1, 2, 4, 8 s), at most MAX_TRIES tries. URLs are allowed by
MPM_WEBHOOK_ALLOW (default loopback only), checked at submission and again, on the
addresses the name resolves to, at each delivery.
"""
from __future__ import annotations

import hashlib
import hmac
import ipaddress
import socket
import time
from urllib.parse import urlsplit

from core.settings import Settings

# core.store.WEBHOOKS, a sorted set: member "job|<id>|<try>" or "sweep|<id>|<try>", score = due time
MAX_TRIES = 5
IN_FLIGHT_SECONDS = 60.0         # a claimed delivery not settled by then is tried again (its worker died)
TIMEOUT_SECONDS = 5.0


class WebhookUrlError(ValueError):
    """A callback URL the settings do not allow; the message says which rule."""


def backoff(tries: int) -> float:
    """Seconds before the next try after `tries` failed ones."""
    return float(2 ** (tries - 1))


def signature(body: bytes, secret: str) -> str:
    return "sha256=" + hmac.new(secret.encode(), body, hashlib.sha256).hexdigest()


def _allowed(settings: Settings) -> tuple[list, set[str]]:
    networks, names = [], set()
    for entry in (part.strip() for part in settings.webhook_allow.split(",")):
        if not entry:
            continue
        try:
            networks.append(ipaddress.ip_network(entry, strict=False))
        except ValueError:
            names.add(entry.lower())
    return networks, names


def check_url(url: str, settings: Settings, resolve: bool = True) -> str:
    """The URL if a webhook may go there: http(s), no credentials, a host that is one of
    MPM_WEBHOOK_ALLOW's names or whose every address is in its networks."""
    if not settings.webhook_secret:
        raise WebhookUrlError("webhooks are off on this service (MPM_WEBHOOK_SECRET is not set)")
    try:
        parts = urlsplit(url)
        parts.port  # noqa: B018 - raises on a bad port
    except ValueError as exc:
        raise WebhookUrlError(f"not a URL: {exc}") from None
    if parts.scheme not in ("http", "https") or not parts.hostname:
        raise WebhookUrlError("must be an http:// or https:// URL with a host")
    if parts.username or parts.password:
        raise WebhookUrlError("must not carry credentials")
    networks, names = _allowed(settings)
    host = parts.hostname.lower()
    if host in names:
        return url
    for address in _addresses(host, parts.port, resolve):
        if not any(address in network for network in networks):
            raise WebhookUrlError(f"host {host} ({address}) is not allowed by MPM_WEBHOOK_ALLOW "
                                  f"({settings.webhook_allow})")
    return url


def _addresses(host: str, port: int | None, resolve: bool) -> list:
    try:
        return [ipaddress.ip_address(host)]
    except ValueError:
        pass
    if not resolve:
        raise WebhookUrlError(f"host {host} is not one of MPM_WEBHOOK_ALLOW's names")
    try:
        infos = socket.getaddrinfo(host, port or 80, type=socket.SOCK_STREAM)
    except OSError as exc:
        raise WebhookUrlError(f"host {host} cannot be resolved: {exc}") from None
    return [ipaddress.ip_address(info[4][0].split("%")[0]) for info in infos]


def member(kind: str, ident: str, tries: int) -> str:
    return f"{kind}|{ident}|{tries}"


def parse_member(text: str) -> tuple[str, str, int]:
    kind, ident, tries = text.split("|")
    return kind, ident, int(tries)


def now() -> float:
    return time.time()
