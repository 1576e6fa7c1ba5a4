"""Fault tests: real processes killed and restarted (no mocks). `mpm serve` runs the
API, a worker and an embedded Redis as a user starts it, with short leases and
frequent checkpoints so that each fault is recovered from in seconds."""
from __future__ import annotations

import sys
from pathlib import Path

import httpx
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "integration"))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from fault_support import Serve  # noqa: E402


@pytest.fixture(scope="module")
def serve(tmp_path_factory):
    serve = Serve(tmp_path_factory.mktemp("fault-data"), tmp_path_factory.mktemp("fault-logs"))
    try:
        yield serve.start()
    finally:
        serve.process.stop(60)


@pytest.fixture
def api(serve):
    with httpx.Client(base_url=serve.url, timeout=30) as client:
        yield client
