"""Process-level domain decomposition (ARCHITECTURE.md, "Process-level domain decomposition").

`decompose(scene, support)` gives the step its domain: `SingleProcess` (no
exchange, no cost) for one process, `SlabDomain` (solver/parallel/mpi.py) for
K processes started by mpiexec. The step calls the same methods either way:
`sum_ghosts`, `share_nodes`, `migrate`, and the collective reductions.

Modules: slabs (which cells, nodes and particles a slab owns; numpy only),
binning (numba: owner of each particle, counting sort into slabs), single (the
one-process domain), mpi (the exchange), launch (mpiexec).
"""
from __future__ import annotations

from solver.parallel import launch   # the scene schema imports solver.parallel.slabs: keep this light


def decompose(scene, support: int):
    """The domain of this process: the whole problem, or its slab when started by mpiexec."""
    from solver.parallel.single import SingleProcess

    started = launch.world()
    if started is None or started[1] == 1:
        if scene.parallel.processes > 1:
            raise ValueError(f"parallel.processes = {scene.parallel.processes}: start the run with "
                             f"`mpm run -n {scene.parallel.processes}` (it launches the processes)")
        return SingleProcess()
    from mpi4py import MPI

    from solver.parallel.mpi import SlabDomain
    return SlabDomain(MPI.COMM_WORLD, scene, support)


def is_root() -> bool:
    """True on rank 0 and in a single-process run: the process that reports and writes."""
    started = launch.world()
    return started is None or started[0] == 0


def all_ranks_done() -> None:
    """Wait for every rank of a run started by mpiexec: a rank that exits with a non-zero
    code (a partial run) makes mpiexec abort the others, and rank 0 may still be writing
    the result's last lines and its report. Nothing to wait for in one process."""
    started = launch.world()
    if started is not None and started[1] > 1:
        from mpi4py import MPI
        MPI.COMM_WORLD.Barrier()
