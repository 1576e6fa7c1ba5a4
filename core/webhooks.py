"""Webhooks: when a job with a `callback_url` ends (or the last job of a sweep with
one), its final record is POSTed there, signed `X-MPM-Signature: sha256=<HMAC-SHA256
of the body with MPM_WEBHOOK_SECRET>`.

A delivery is queued in Redis by the same script that finishes the job (core/store.py),
so every way a job ends notifies once; the workers' sender threads (worker/webhooks.py)
deliver it, never a task or a request: a slow receiver blocks nobody. A failed try is
retried with backoff (1, 2, 4, 8 s), at most MAX_TRIES tries. URLs are allowed by
MPM_WEBHOOK_ALLOW (default: loopback, unprivileged ports only), never the service's own
Redis, checked at submission and again at each delivery, which connects to the very
address that check resolved (no second lookup).
"""
from __future__ import annotations

import hashlib
import hmac
import ipaddress
import re
import socket
import time
from dataclasses import dataclass
from typing import Any
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


# Characters a URL must not hold: C0 controls (CR, LF: header injection when the URL reaches
# the request line), DEL, the C1 controls and spaces. (urllib and http.client refuse some at
# delivery with exceptions of their own; the rule refuses them all at submission.)
_FORBIDDEN = re.compile(r"[\x00-\x20\x7f-\x9f]")


@dataclass(frozen=True)
class _Entry:
    """One MPM_WEBHOOK_ALLOW entry: a network or a host name, and the ports it allows."""
    network: Any            # ipaddress network, or None for a name
    name: str | None
    ports: tuple[int, int]  # first, last (1-65535 when the entry gives none)

    def admits(self, host: str, address: Any, port: int) -> bool:
        if not self.ports[0] <= port <= self.ports[1]:
            return False
        return host == self.name if self.network is None else address is not None and address in self.network


def _entry(text: str) -> _Entry:
    """`127.0.0.0/8`, `localhost`, `::1`, with an optional `:PORT` or `:FIRST-LAST`
    (`127.0.0.0/8:1024-65535`, `[::1]:8000`, `hooks.example.org:443`)."""
    host, ports = text, ""
    if text.startswith("["):
        host, _, rest = text[1:].partition("]")
        ports = rest.removeprefix(":")
    elif text.count(":") == 1:
        host, ports = text.split(":")
    first, _, last = ports.partition("-")
    try:
        span = (int(first), int(last or first)) if first else (1, 65535)
    except ValueError:   # a mistyped port admits nothing rather than everything
        span = (1, 0)
    try:
        return _Entry(ipaddress.ip_network(host, strict=False), None, span)
    except ValueError:
        return _Entry(None, host.lower(), span)


def _allowed(settings: Settings) -> list[_Entry]:
    return [_entry(part.strip()) for part in settings.webhook_allow.split(",") if part.strip()]


def _own_redis(settings: Settings) -> tuple[str, int] | None:
    """(host, port) of the service's Redis: never a webhook's target, whatever the allow-list."""
    if not settings.redis_url:
        return None
    try:
        parts = urlsplit(settings.redis_url)
        return (parts.hostname or "localhost").lower(), parts.port or 6379
    except ValueError:
        return None


def check_url(url: str, settings: Settings, resolve: bool = True) -> str:
    """The URL if a webhook may go there (see `checked_target`); WebhookUrlError naming the rule."""
    checked_target(url, settings, resolve)
    return url


def checked_target(url: str, settings: Settings, resolve: bool = True) -> tuple[str, int, Any]:
    """(host, port, the address to connect to) of a URL a webhook may go to: http(s), no
    control characters or spaces, no credentials, a host:port that MPM_WEBHOOK_ALLOW admits
    (a name listed, or every address it resolves to in a listed network, on a listed port),
    never the service's own Redis. The delivery connects to the address returned, so the
    name is not resolved a second time (DNS rebinding: a name that answered an allowed
    address to the check and another to the connection)."""
    bad = _FORBIDDEN.search(url)   # malformed whether or not webhooks are on: said first
    if bad:
        raise WebhookUrlError(f"must not contain control characters or spaces (U+{ord(bad.group()):04X} at "
                              f"position {bad.start()})")
    if not url.lower().startswith(("http://", "https://")):
        raise WebhookUrlError("must be an http:// or https:// URL with a host")
    if not settings.webhook_secret:
        raise WebhookUrlError("webhooks are off on this service (MPM_WEBHOOK_SECRET is not set)")
    try:
        parts = urlsplit(url)
        port = parts.port or (443 if parts.scheme == "https" else 80)
    except ValueError as exc:
        raise WebhookUrlError(f"not a URL: {exc}") from None
    if parts.scheme not in ("http", "https") or not parts.hostname:
        raise WebhookUrlError("must be an http:// or https:// URL with a host")
    if parts.username or parts.password:
        raise WebhookUrlError("must not carry credentials")
    host = parts.hostname.lower()
    entries = _allowed(settings)
    addresses = _addresses(host, port, resolve or any(e.name == host for e in entries))
    redis_target = _own_redis(settings)
    for address in addresses:
        if redis_target and port == redis_target[1] and (address.is_loopback or str(address) == redis_target[0]
                                                           or host == redis_target[0]):
            raise WebhookUrlError(f"port {port} of {host} is the service's own Redis (MPM_REDIS_URL)")
        if any(entry.admits(host, None, port) for entry in entries if entry.network is None):
            continue
        if not any(entry.admits(host, address, port) for entry in entries if entry.network is not None):
            raise WebhookUrlError(f"host {host} ({address}) port {port} is not allowed by MPM_WEBHOOK_ALLOW "
                                  f"({settings.webhook_allow})")
    return host, port, addresses[0]


def _addresses(host: str, port: int, resolve: bool) -> list:
    try:
        return [ipaddress.ip_address(host)]
    except ValueError:
        pass
    if not resolve:
        raise WebhookUrlError(f"host {host} is not one of MPM_WEBHOOK_ALLOW's names")
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    except (OSError, UnicodeError) as exc:
        raise WebhookUrlError(f"host {host} cannot be resolved: {exc}") from None
    if not infos:
        raise WebhookUrlError(f"host {host} resolves to no address")
    return [ipaddress.ip_address(info[4][0].split("%")[0]) for info in infos]


def member(kind: str, ident: str, tries: int) -> str:
    return f"{kind}|{ident}|{tries}"


def parse_member(text: str) -> tuple[str, str, int]:
    kind, ident, tries = text.split("|")
    return kind, ident, int(tries)


def now() -> float:
    return time.time()
