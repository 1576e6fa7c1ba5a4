"""Starting K processes: the mpiexec of the MPI installed beside this Python.

The MPI comes from the package registry (the `mpich` wheel puts `mpiexec` into
the environment's bin folder), so no system MPI is needed. Processes start on
this machine without ssh (MPICH hydra: the fork launcher; Open MPI: more
processes than cores allowed). Ranks run `python -m mpi4py -m solver ...`: an
uncaught error in one rank aborts them all instead of leaving the others waiting.
"""
from __future__ import annotations

import os
import shutil
import sys
from pathlib import Path

# Environment of the launch: local processes only, oversubscription allowed (CI has 2 cores).
LAUNCH_ENV = {
    "HYDRA_LAUNCHER": "fork",                          # MPICH
    "OMPI_MCA_rmaps_base_oversubscribe": "true",       # Open MPI 4
    "PRTE_MCA_rmaps_default_mapping_policy": ":oversubscribe",   # Open MPI 5
}


def mpiexec() -> str:
    """The mpiexec beside this interpreter (the virtual environment's), else the one on PATH."""
    beside = Path(sys.executable).parent / "mpiexec"
    if beside.exists():
        return str(beside)
    found = shutil.which("mpiexec")
    if found is None:
        raise RuntimeError("no mpiexec found: install the project's dependencies (the mpich wheel provides it)")
    return found


def python(processes: int, *args: str) -> list[str]:
    """`mpiexec -n K python -m mpi4py <args>`: K ranks of this interpreter."""
    return [mpiexec(), "-n", str(processes), sys.executable, "-m", "mpi4py", *args]


def command(processes: int, solver_args: list[str]) -> list[str]:
    """`mpiexec -n K python -m mpi4py -m solver <solver_args>`."""
    return python(processes, "-m", "solver", *solver_args)


def environment() -> dict[str, str]:
    return {**os.environ, **LAUNCH_ENV}


def world() -> tuple[int, int] | None:
    """(rank, size) when this process was started by mpiexec, from the launcher's
    environment (without initialising MPI); None otherwise."""
    for rank_key, size_key in (("PMI_RANK", "PMI_SIZE"), ("OMPI_COMM_WORLD_RANK", "OMPI_COMM_WORLD_SIZE")):
        if size_key in os.environ:
            return int(os.environ.get(rank_key, 0)), int(os.environ[size_key])
    return None
