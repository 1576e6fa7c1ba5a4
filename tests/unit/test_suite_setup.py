"""The suite's own set-up (tests/conftest.py): each pytest-xdist worker runs a scene that names no
thread count on its share of the cores, as a service worker gives each job its share."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

from solver.thread_count import available_cores

CONFTEST = Path(__file__).resolve().parent.parent / "conftest.py"
SEEN = """
import os
from pathlib import Path

def test_seen():
    Path(os.environ["SEEN_FILE"]).write_text(os.environ["MPM_CORES"])
"""


def cores_seen(tmp_path: Path, workers: int, environment: dict) -> int:
    folder = tmp_path / f"run{len(list(tmp_path.iterdir()))}"
    folder.mkdir()
    shutil.copy(CONFTEST, folder / "conftest.py")
    (folder / "test_seen.py").write_text(SEEN)
    seen = folder / "seen.txt"
    command = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "--rootdir", str(folder), str(folder)]
    done = subprocess.run(command + (["-n", str(workers)] if workers else ["-p", "no:xdist"]), cwd=folder,
                          env={**environment, "SEEN_FILE": str(seen), "PYTHONPATH": str(CONFTEST.parent.parent)},
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stdout + done.stderr
    return int(seen.read_text())


def test_each_worker_takes_its_share_of_the_cores(tmp_path):
    environment = {name: value for name, value in os.environ.items()
                   if not name.startswith(("MPM_CORES", "MPM_TEST_", "PYTEST_"))}
    cores = available_cores({})
    assert cores_seen(tmp_path, 0, environment) == cores
    assert cores_seen(tmp_path, 2, environment) == max(1, cores // 2)
    assert cores_seen(tmp_path, 0, {**environment, "MPM_CORES": "3"}) == 3   # the command line's choice stands
