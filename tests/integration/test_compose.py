"""docker-compose.yml parses (there is no Docker engine here to run it)."""
from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _compose() -> list[str] | None:
    if shutil.which("docker") and subprocess.run(["docker", "compose", "version"],
                                                 capture_output=True).returncode == 0:
        return ["docker", "compose"]
    if shutil.which("docker-compose"):
        return ["docker-compose"]
    return None


def test_compose_file_parses_with_redis_api_and_scalable_workers():
    # scripts/dev.py installs Debian's docker-compose for this check when no compose is present
    assert _compose() is not None, "neither `docker compose` nor docker-compose is installed: apt-get install docker-compose"
    done = subprocess.run([*_compose(), "-f", str(ROOT / "docker-compose.yml"), "config", "--services"],
                          capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    assert set(done.stdout.split()) == {"redis", "api", "worker"}
    config = subprocess.run([*_compose(), "-f", str(ROOT / "docker-compose.yml"), "config"],
                            capture_output=True, text=True, cwd=ROOT).stdout
    assert "appendonly" in config and "results:/data" in config
    assert re.search(r"appendfsync\W+always", config)   # as the embedded one (docs/reliability.md)
    # scalable: no fixed container name or host port on the worker
    worker = config.split("  worker:", 1)[1]
    assert "container_name" not in worker and "ports" not in worker
