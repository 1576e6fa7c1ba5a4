"""Numba kernels that sort particles by slab: who owns each particle, and the
per-slab lists (a counting sort, as MPM3DMP 4.1.2 bins particles into patches)."""
from __future__ import annotations

import numpy as np
from solver.jit import njit


@njit(cache=True)
def owners(x_axis, lower, inv_h, cuts, me, out):
    """out[p] = the slab owning particle p (by its cell layer, clipped into the grid;
    a non-finite position stays with `me`, whose checks report it). Returns how many leave `me`."""
    k = cuts.size - 1
    n_cells = cuts[k]
    leaving = 0
    for p in range(x_axis.shape[0]):
        s = (x_axis[p] - lower) * inv_h
        if not np.isfinite(s):
            out[p] = me
            continue
        layer = min(max(int(np.floor(s)), 0), n_cells - 1)
        r = 0
        while cuts[r + 1] <= layer:
            r += 1
        out[p] = r
        if r != me:
            leaving += 1
    return leaving


@njit(cache=True)
def bin_particles(patch, n_patches, n_threads):
    """Counting sort of particles into patches, as MPM3DMP 4.1.2 builds its per-patch lists.

    Thread t takes the t-th contiguous block of particles and counts how many
    fall in each patch (patnp_th[t, j]); patnp[j] = sum_t patnp_th[t, j]; each
    thread then writes its particles at its own offset inside each patch's
    block, so the blocks fill without locks and in particle order. Returns
    (patnp_th, patnp, order, start): order[start[j]:start[j+1]] are the
    indices of the particles of patch j.
    """
    n = patch.shape[0]
    bounds = np.empty(n_threads + 1, dtype=np.int64)
    for t in range(n_threads + 1):
        bounds[t] = (t * n) // n_threads
    patnp_th = np.zeros((n_threads, n_patches), dtype=np.int64)
    for t in range(n_threads):
        for p in range(bounds[t], bounds[t + 1]):
            patnp_th[t, patch[p]] += 1
    patnp = np.zeros(n_patches, dtype=np.int64)
    for t in range(n_threads):
        for j in range(n_patches):
            patnp[j] += patnp_th[t, j]
    start = np.zeros(n_patches + 1, dtype=np.int64)
    for j in range(n_patches):
        start[j + 1] = start[j] + patnp[j]
    offset = np.empty((n_threads, n_patches), dtype=np.int64)   # where thread t writes into patch j
    for j in range(n_patches):
        at = start[j]
        for t in range(n_threads):
            offset[t, j] = at
            at += patnp_th[t, j]
    order = np.empty(n, dtype=np.int64)
    for t in range(n_threads):
        for p in range(bounds[t], bounds[t + 1]):
            j = patch[p]
            order[offset[t, j]] = p
            offset[t, j] += 1
    return patnp_th, patnp, order, start
