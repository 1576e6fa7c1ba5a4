"""Webhooks against hostile URLs (issue 49): the URL rule at submission, the address the
delivery connects to, and a sender thread that no delivery can stop. A real receiver on
127.0.0.1; Redis is a small fake that holds the queue (the sender's only use of it)."""
from __future__ import annotations

import socket
import sys
import time
from pathlib import Path

import pytest

from core import webhooks
from core.settings import Settings
from worker import webhooks as sender_module
from worker.webhooks import WebhookSender

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "integration"))
from webhook_receiver import Receiver  # noqa: E402

SETTINGS = Settings(webhook_secret="s3cret", redis_url="redis://:pw@127.0.0.1:6390/0")


@pytest.mark.parametrize("url,words", [
    ("http://127.0.0.1:9911/\r\nX-Injected: 1", "control characters"),
    ("http://127.0.0.1:9911/a\nb", "control characters"),
    ("http://127.0.0.1:9911/a\x00", "control characters"),
    ("http://127.0.0.1:9911/a b", "spaces"),
    ("gopher://127.0.0.1:9911/", "http:// or https://"),
    ("javascript:alert(1)", "http:// or https://"),
    ("http://127.0.0.1:6390/", "the service's own Redis"),   # MPM_REDIS_URL's port
    ("http://localhost:6390/", "the service's own Redis"),
    ("http://127.0.0.1:22/", "not allowed by MPM_WEBHOOK_ALLOW"),   # a privileged loopback port
    ("http://127.0.0.1/", "not allowed by MPM_WEBHOOK_ALLOW"),
])
def test_a_url_that_breaks_a_rule_is_refused_naming_it(url, words):
    with pytest.raises(webhooks.WebhookUrlError, match=words):
        webhooks.check_url(url, SETTINGS)


def test_allowed_urls_and_ports_given_in_the_allow_list():
    assert webhooks.check_url("http://127.0.0.1:9911/hook?x=1", SETTINGS)
    assert webhooks.check_url("https://[::1]:8443/", SETTINGS)
    custom = Settings(webhook_secret="s", webhook_allow="10.1.0.0/16:443,hooks.example.org:8080,[::1]:80")
    assert webhooks.checked_target("https://10.1.2.3/x", custom, resolve=False)[2] == webhooks.ipaddress.ip_address("10.1.2.3")
    assert webhooks.checked_target("http://[::1]/", custom)[1] == 80
    with pytest.raises(webhooks.WebhookUrlError):
        webhooks.check_url("http://10.1.2.3:444/x", custom, resolve=False)
    with pytest.raises(webhooks.WebhookUrlError):   # a mistyped port admits nothing
        webhooks.check_url("http://127.0.0.1:9000/", Settings(webhook_secret="s", webhook_allow="127.0.0.1:9x"))


def test_the_delivery_connects_to_the_address_that_was_checked(monkeypatch):
    """DNS rebinding: the name answers an allowed address to the check, another afterwards.
    One lookup per delivery, and the connection goes to the address that lookup checked."""
    lookups = []
    real = socket.getaddrinfo

    def rebinding(host, port, *args, **kwargs):
        if host != "rebind.test":
            return real(host, port, *args, **kwargs)
        lookups.append(host)
        address = "127.0.0.1" if len(lookups) == 1 else "10.255.255.1"   # then somewhere not allowed
        return [(socket.AF_INET, socket.SOCK_STREAM, 6, "", (address, port))]

    monkeypatch.setattr(socket, "getaddrinfo", rebinding)
    with Receiver() as receiver:
        port = receiver.server.server_address[1]
        failure = sender_module.post(f"http://rebind.test:{port}/hook", b"{}", {"X-Test": "1"}, SETTINGS)
    assert failure is None and len(lookups) == 1
    assert len(receiver.requests) == 1 and receiver.requests[0]["headers"]["host"] == f"rebind.test:{port}"


class _FakeRedis:
    """The queue of deliveries (a dict member -> due time) and what the sender calls on it."""

    def __init__(self) -> None:
        self.queue: dict[str, float] = {}

    def register_script(self, _text: str):
        def claim(keys, args):
            due = [m for m, t in self.queue.items() if t <= args[0]][:10]
            for member in due:
                self.queue[member] = args[1]
            return due
        return claim

    def zrem(self, _key: str, member: str) -> None:
        self.queue.pop(member, None)

    def zadd(self, _key: str, mapping: dict[str, float]) -> None:
        self.queue.update(mapping)

    def pipeline(self) -> "_FakeRedis":
        return self

    def execute(self) -> None:
        pass


class _FakeStore:
    def __init__(self, urls: dict[str, str]) -> None:
        self.redis = _FakeRedis()
        self.records = {ident: {"id": ident, "status": "succeeded", "callback_url": url} for ident, url in urls.items()}

    def get(self, ident: str):
        return self.records.get(ident)


def test_no_url_and_no_exception_stops_the_later_deliveries(monkeypatch):
    """Issue 49: a CR/LF URL stored before the rule existed raised http.client.InvalidURL in
    the thread, and no later webhook was delivered. Every bad one now settles alone."""
    with Receiver() as receiver:
        urls = {"crlf": "http://127.0.0.1:9911/\r\nX-Injected: 1", "nul": "http://127.0.0.1:9911/\x00",
                "scheme": "file:///etc/passwd", "raises": receiver.url + "/raises", "good": receiver.url + "/good"}
        store = _FakeStore(urls)
        real_post = sender_module.post

        def post(url, *args):
            if url.endswith("/raises"):
                raise RuntimeError("a bug in a delivery")
            return real_post(url, *args)
        monkeypatch.setattr(sender_module, "post", post)
        sender = WebhookSender(store, SETTINGS, interval=0.05)
        for ident in urls:
            store.redis.queue[webhooks.member("job", ident, 1)] = 0.0
        store.redis.queue["garbage-member"] = 0.0   # not even a delivery: it must not stop the rest
        sender.start()
        try:
            deadline = time.monotonic() + 10
            while not receiver.requests and time.monotonic() < deadline:
                time.sleep(0.05)
        finally:
            sender.stop()
        assert [r["path"] for r in receiver.requests] == ["/good"]
        assert sender._thread.is_alive() is False   # stopped by us, not by a delivery
        assert not any(m.startswith(("job|crlf", "job|nul", "job|scheme", "job|raises", "garbage"))
                       for m in store.redis.queue), store.redis.queue   # given up, not retried for ever
