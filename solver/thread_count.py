"""How many threads a run takes, decided without numba (the service's estimates read it too).

solver/threads.py sets the count for a process; this module only computes it.
"""
from __future__ import annotations

import os

# Automatic thread counts give each thread at least this many particles: below it the
# start of a parallel loop and the sum of the grid copies outweigh the work (a
# 224-particle job ran at 40 steps/s on two threads beside another job).
PARTICLES_PER_THREAD = 4000


def available_cores(environment=os.environ) -> int:
    """The cores a run in `environment` may use: MPM_CORES when set (a worker running several
    jobs at once gives each its share), else the cores this process may run on."""
    if environment.get("MPM_CORES", "").isdigit() and int(environment["MPM_CORES"]) > 0:
        return int(environment["MPM_CORES"])
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:   # not on Linux
        return os.cpu_count() or 1


def requested_threads(scene, particles: int) -> int:
    """The scene's `parallel.threads` when set; 0 takes the cores shared among the
    processes, at most one thread per PARTICLES_PER_THREAD particles (all processes')."""
    processes = scene.parallel.processes
    by_size = max(1, particles // (processes * PARTICLES_PER_THREAD))
    return scene.parallel.threads or min(max(1, available_cores() // processes), by_size)


def pool_size() -> int:
    """numba's thread pool without starting numba: NUMBA_NUM_THREADS, else the CPUs it sees."""
    given = os.environ.get("NUMBA_NUM_THREADS", "")
    return int(given) if given.isdigit() and int(given) > 0 else (os.cpu_count() or 1)
