"""Fixtures of the SDK tests: clients wired to a scripted fake of the HTTP API
(offline), and a real service (`mpm serve`) for the live tests."""
from __future__ import annotations

from typing import Callable, Iterator

import httpx
import pytest

from live_service import LiveService, shared_service
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


@pytest.fixture(scope="session")
def live(pytestconfig: pytest.Config, tmp_path_factory: pytest.TempPathFactory) -> LiveService:
    return shared_service(pytestconfig, tmp_path_factory)


@pytest.fixture
def live_client(live: LiveService) -> Iterator[Client]:
    with Client(live.url, timeout=60) as sdk:
        yield sdk
