"""Fixtures of the SDK tests: clients wired to a scripted fake of the HTTP API (offline)."""
from __future__ import annotations

from typing import Callable, Iterator

import httpx
import pytest

from mpm_client import AsyncClient, Client
from sdk_fakes import BASE, FakeService


@pytest.fixture
def fake() -> FakeService:
    return FakeService()


@pytest.fixture
def client(fake: FakeService) -> Iterator[Client]:
    with Client(BASE, token="secret", backoff=0.0, transport=httpx.MockTransport(fake)) as sdk:
        yield sdk


@pytest.fixture
def async_client_factory(fake: FakeService) -> Callable[[], AsyncClient]:
    return lambda: AsyncClient(BASE, token="secret", backoff=0.0, transport=httpx.MockTransport(fake))
