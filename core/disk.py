"""The size of the jobs' folders: measured by the workers while a job runs (worker/disk.py)
and by the API before it admits one (service/quotas.py)."""
from __future__ import annotations

import os
import shutil
import threading
import time
from pathlib import Path


def folder_bytes(path: Path) -> int:
    """The size of the files under `path` (0 when it does not exist)."""
    total = 0
    try:
        entries = list(os.scandir(path))
    except OSError:
        return 0
    for entry in entries:
        try:
            if entry.is_dir(follow_symlinks=False):
                total += folder_bytes(Path(entry.path))
            elif entry.is_file(follow_symlinks=False):
                total += entry.stat(follow_symlinks=False).st_size
        except OSError:  # removed while we looked
            continue
    return total


def human(count: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB"):
        if count < 1024:
            return f"{count:.0f} {unit}" if unit == "B" else f"{count:.1f} {unit}"
        count /= 1024
    return f"{count:.1f} TiB"


class DiskUsage:
    """The jobs' folders' total and the file system's free space, measured again at most
    every `max_age` seconds (a walk of every folder), for the admission of each job."""

    def __init__(self, jobs_dir: Path, max_age: float = 5.0):
        self.jobs_dir, self.max_age = Path(jobs_dir), max_age
        self._lock = threading.Lock()
        self._measured_at = -float("inf")
        self._value = (0, 0)

    def measure(self) -> tuple[int, int]:
        """(bytes of all the jobs' folders, bytes free on their file system)."""
        with self._lock:
            if time.monotonic() - self._measured_at > self.max_age:
                self.jobs_dir.mkdir(parents=True, exist_ok=True)
                self._value = (folder_bytes(self.jobs_dir), shutil.disk_usage(self.jobs_dir).free)
                self._measured_at = time.monotonic()
            return self._value
