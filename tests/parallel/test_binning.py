"""Slab geometry and the particle binning of domain decomposition (no MPI needed)."""
from __future__ import annotations

import numpy as np
import pytest

from solver.parallel.binning import bin_particles, owners
from solver.parallel.slabs import balanced_cuts, even_cuts, local_nodes, owned_nodes, split_axis


def test_mpm3dmp_binning_example_reproduces_patnp_and_pindex():
    """E34 (MPM3DMP 4.1.2, Fig. 5): 16 particles, 4 patches, 4 threads of 4 particles each."""
    members = {1: [2, 3, 5, 11], 2: [1, 6, 7, 16], 3: [8, 10, 14], 4: [4, 9, 12, 13, 15]}
    patch = np.zeros(16, dtype=np.int64)
    for j, ids in members.items():
        patch[np.array(ids) - 1] = j - 1
    patnp_th, patnp, order, start = bin_particles(patch, 4, 4)

    assert patnp_th.tolist() == [[2, 1, 0, 1], [1, 2, 1, 0], [1, 0, 1, 2], [0, 1, 1, 2]]
    assert patnp.tolist() == [4, 4, 3, 5]
    pindex = np.zeros((patnp.max(), 4), dtype=np.int64)   # global ids, zero padded, as the paper prints it
    for j in range(4):
        ids = order[start[j]:start[j + 1]] + 1
        pindex[:ids.size, j] = ids
    assert pindex.tolist() == [[2, 1, 8, 4], [3, 6, 10, 9], [5, 7, 14, 12], [11, 16, 0, 13], [0, 0, 0, 15]]


@pytest.mark.parametrize("threads", [1, 3, 7])
def test_binning_is_a_stable_counting_sort_for_any_thread_count(threads):
    rng = np.random.default_rng(3)
    patch = rng.integers(0, 5, size=1000)
    _, patnp, order, start = bin_particles(patch, 5, threads)
    assert np.array_equal(order, np.argsort(patch, kind="stable"))
    assert np.array_equal(patnp, np.bincount(patch, minlength=5)) and start[-1] == 1000


def test_slabs_split_the_longest_axis_and_balance_particle_counts():
    assert split_axis([40, 60, 60]) == 2 and split_axis([80, 20]) == 0
    assert even_cuts(10, 3).tolist() == [0, 3, 6, 10]
    # all particles in the upper half of 20 layers: the cut moves into that half
    per_layer = np.r_[np.zeros(10, np.int64), np.full(10, 7)]
    cuts = balanced_cuts(per_layer, 2)
    assert cuts.tolist() == [0, 15, 20]
    # every slab keeps at least one layer, even when one layer holds everything
    assert np.all(np.diff(balanced_cuts(np.r_[np.zeros(9, np.int64), [100]], 4)) >= 1)


@pytest.mark.parametrize("support", [2, 3, 4])
def test_each_slab_keeps_the_nodes_its_particles_touch(support):
    """Local nodes cover every node a centred stencil of SUPPORT nodes reaches from the slab's cells;
    owned node layers partition the grid."""
    cuts = np.array([0, 4, 5, 12])
    below, above = (support - 1) // 2, (support + 1) // 2
    owned = [set(range(*owned_nodes(cuts, r))) for r in range(3)]
    assert set().union(*owned) == set(range(13)) and sum(map(len, owned)) == 13
    for r in range(3):
        lo, hi = local_nodes(cuts, r, support)
        for cell in range(cuts[r], cuts[r + 1]):
            for s in np.linspace(cell, cell + 1, 11)[:-1]:   # positions across the cell
                base = int(np.floor(s - (support - 2) / 2)) if support > 2 else cell
                touched = {n for n in range(base, base + support) if 0 <= n <= 12}
                assert touched <= set(range(lo, hi)), (r, s)
        assert lo >= cuts[r] - below and hi <= cuts[r + 1] + above


def test_owners_follow_the_cell_layer_and_keep_non_finite_positions():
    cuts = np.array([0, 3, 7, 10])
    x = np.array([0.05, 0.31, 0.69, 0.7, 1.2, -0.5, np.nan])
    dest = np.empty(x.size, dtype=np.int64)
    leaving = owners(x, 0.0, 10.0, cuts, 1, dest)
    assert dest.tolist() == [0, 1, 1, 2, 2, 0, 1] and leaving == 4
