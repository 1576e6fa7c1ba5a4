"""Fixtures of the security tests: a service with API tokens (`mpm serve`, shared with
the dashboard's token test) and clients with each owner's token."""
from __future__ import annotations

import sys
from pathlib import Path
from typing import Iterator

import httpx
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "integration"))

from secure_service import SecureService, bearer, shared_secure_service  # noqa: E402


@pytest.fixture(scope="session")
def secure(pytestconfig, tmp_path_factory) -> SecureService:
    return shared_secure_service(pytestconfig, tmp_path_factory)


def _client(url: str, owner: str | None) -> httpx.Client:
    return httpx.Client(base_url=url, timeout=60, headers=bearer(owner) if owner else None)


@pytest.fixture
def alice(secure) -> Iterator[httpx.Client]:
    with _client(secure.url, "alice") as client:
        yield client


@pytest.fixture
def bob(secure) -> Iterator[httpx.Client]:
    with _client(secure.url, "bob") as client:
        yield client
