"""Threads inside one process: how many, and how the particle loops share them.

Every threaded kernel splits the particles into one contiguous block per thread
(`block_bounds`) and runs the blocks with numba's prange. Gathers (G2P, the
kinematics, the materials) write only their own particle's rows, so they are
race-free as they stand and give the same bits for any thread count.

Scatters (P2G) would race where two particles of different blocks share a node.
Each thread adds its block into its own copy of the nodal arrays instead, and
the copies are summed node by node afterwards (`ScatterCopies`); thread 0 adds
straight into the grid, so one thread costs nothing extra. The sums then differ
between thread counts only in the order of the additions: round-off.
The alternative, particles binned by cell each step and processed in coloured
blocks of cells, was measured against this (benchmarks/p2g_strategies.py): the
counting sort and the indirect particle access cost more than summing the
copies of a grid of this size, on this machine (docs/benchmarks.md).

The count comes from the scene's `parallel.threads`; 0 (the default) means the
cores this run may use, shared among its processes, and no more threads than
the particles keep busy (PARTICLES_PER_THREAD; solver/thread_count.py decides the count
without numba, for the run-time estimates too).
"""
from __future__ import annotations

import os

# Between parallel loops numba's OpenMP threads spin, then sleep. Spinning for long
# (libgomp's default) took the core that the serial phases of the step needed on a
# shared, loaded machine (a serial kernel ran 50x slower); sleeping at once
# (OMP_WAIT_POLICY=PASSIVE) costs a wake-up per loop, and two threads ran the 2D
# block of benchmarks/throughput.py only 1.25x faster than one. A short spin, about
# the length of the serial gaps in a step, gave 1.85x (docs/benchmarks.md, "Threads").
# An environment that sets either variable keeps its own.
if "OMP_WAIT_POLICY" not in os.environ:
    os.environ.setdefault("GOMP_SPINCOUNT", "100000")

import numba  # noqa: E402  (after the policy: OpenMP reads it when numba first starts its threads)
import numpy as np  # noqa: E402
from solver.jit import njit, use_threads  # noqa: E402

from solver.thread_count import PARTICLES_PER_THREAD, available_cores, requested_threads  # noqa: E402,F401


def configure(scene, particles: int) -> int:
    """Set numba's thread count for this process from the scene; returns it.

    `particles`: the scene's particles (all processes). The scene's `threads`, when
    set, is taken as it is; 0 takes the cores shared among the processes, at most one
    thread per PARTICLES_PER_THREAD particles. numba's pool is sized at start-up
    (NUMBA_NUM_THREADS, by default the cores it sees): a request beyond it is capped there."""
    threads = max(1, min(requested_threads(scene, particles), numba.config.NUMBA_NUM_THREADS))
    numba.set_num_threads(threads)
    use_threads(threads)
    return threads


@njit(cache=True)
def block_bounds(n, blocks):
    """Start of each of `blocks` near-equal contiguous blocks of range(n), and n."""
    bounds = np.empty(blocks + 1, dtype=np.int64)
    for b in range(blocks + 1):
        bounds[b] = (n * b) // blocks
    return bounds


class ScatterCopies:
    """Per-thread copies of the nodal arrays a P2G kernel adds into, beyond the first.

    `mass` is (threads - 1, n_nodes), `momentum` and `force` (threads - 1, n_nodes,
    dim); with one thread they are empty and the kernels add into the grid alone.
    """

    def __init__(self, n_nodes: int, dim: int, threads: int):
        extra = threads - 1
        self.mass = np.zeros((extra, n_nodes))
        self.momentum = np.zeros((extra, n_nodes, dim))
        self.force = np.zeros((extra, n_nodes, dim))


@njit(cache=True, inline="always")
def _add_copies_at(mass, momentum, force, copies_mass, copies_momentum, copies_force, i, dim):
    for t in range(copies_mass.shape[0]):
        mass[i] += copies_mass[t, i]
        for a in range(dim):
            momentum[i, a] += copies_momentum[t, i, a]
            force[i, a] += copies_force[t, i, a]


@njit(parallel=True, cache=True)
def add_copies(dims, mass, momentum, force, copies_mass, copies_momentum, copies_force):
    """Add the copies into the grid's arrays, node by node (the nodes split among threads);
    `dims` makes the dimension a compile-time constant, so that the component loop unrolls
    (solver/kernels.py `axes`)."""
    for i in numba.prange(momentum.shape[0]):
        _add_copies_at(mass, momentum, force, copies_mass, copies_momentum, copies_force, i, len(dims))


@njit(cache=True)
def own(t, grid_array, copies):
    """The array block t adds into: the grid's own for block 0, its zeroed copy otherwise."""
    if t == 0:
        return grid_array
    mine = copies[t - 1]
    mine.fill(0.0)
    return mine


@njit(cache=True)
def own_zeroed(t, grid_array, copies):
    """`own`, the grid's array zeroed by block 0 as well: the zeroing then runs in the threads
    beside the copies' instead of before the kernel, in one."""
    mine = grid_array if t == 0 else copies[t - 1]
    mine.fill(0.0)
    return mine


@njit(parallel=True, cache=True)
def add_node_copies(grid_array, copies):
    """grid_array += the sum of its copies (n_nodes or (n_nodes, dim)), node by node."""
    flat = grid_array.reshape(-1)
    copies_flat = copies.reshape(copies.shape[0], -1)
    for i in numba.prange(flat.shape[0]):
        for t in range(copies_flat.shape[0]):
            flat[i] += copies_flat[t, i]


@njit(cache=True)
def first_of(bad):
    """The lowest particle index any block reported (blocks are in particle order), or -1."""
    for b in bad:
        if b >= 0:
            return b
    return -1
