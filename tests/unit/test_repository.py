"""The repository stays small enough to clone: no tracked file is over 2 MiB, except the
fixtures named here, each with the reason it has to be that size. Large build artefacts
(wheels, outputs, caches) belong in a package index or in .gitignore, not in git."""
from __future__ import annotations

import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
LIMIT_BYTES = 2 * 1024 * 1024

# The regression suite's recorded results: every example's fields, compared bit for bit
# (tests/regression/test_regression.py); splitting it would not make a clone smaller.
LARGE_FIXTURES = {"tests/regression/baseline.npz"}


def tracked_files() -> list[str]:
    listed = subprocess.run(["git", "ls-files", "-z"], cwd=ROOT, capture_output=True, check=True)
    return [name for name in listed.stdout.decode().split("\0") if name]


def test_no_tracked_file_is_over_two_mebibytes():
    too_large = {name: (ROOT / name).stat().st_size for name in tracked_files()
                 if name not in LARGE_FIXTURES and (ROOT / name).is_file()
                 and (ROOT / name).stat().st_size > LIMIT_BYTES}
    assert not too_large, f"tracked files over {LIMIT_BYTES} bytes: {too_large}"


def test_the_named_fixtures_are_still_tracked():
    """An allowance for a file that is gone would let a new large file of that name in unseen."""
    assert LARGE_FIXTURES <= set(tracked_files())
