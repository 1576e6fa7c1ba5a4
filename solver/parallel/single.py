"""The domain of a run on one process: the whole grid, every particle, no exchange.

It offers the same methods as the MPI slab domain (solver/parallel/mpi.py) so
that the step reads the same for one process and for K; here each of them does
nothing, or returns its argument.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from solver import shape
from solver.boundary import Constraints
from solver.results import ResultWriter
from solver.state import make_grid

# What migrate() changed: nothing, the particles held here, or also the slabs (grid and constraints).
UNCHANGED, PARTICLES_MOVED, SLABS_MOVED = 0, 1, 2


class SingleProcess:
    processes = 1
    rank = 0
    is_root = True

    def grid(self, scene):
        return make_grid(scene)

    def constraints(self, scene, grid):
        return Constraints(scene, grid)

    def owned(self, whole, grid):
        """Nodal conditions of the whole grid (node, axis, value) on this process's nodes: all of them."""
        return whole

    def weights(self, module, spec, x, particles, grid, stencil) -> int:
        return shape.evaluate(module, spec, x, particles, grid, stencil)

    def frame(self, grid):
        """Where the fused kernels (solver/fused.py) place particles: the whole grid's
        origin, cells and spacing, and the node numbering of this process's grid."""
        return SimpleNamespace(lower=grid.lower, h=grid.h, inv_h=grid.inv_h, cells=grid.cells,
                               strides=grid.strides, offset=0)

    def distribute(self, particles) -> None:
        pass

    def first_node(self, axis: int) -> int:
        return 0

    def owned_local(self, nodes):
        return nodes

    def owned_mask(self, grid):
        """Which nodes of the grid this process owns: all of them."""
        return np.ones(grid.n_nodes, dtype=np.bool_)

    def sum_ghosts(self, *node_arrays) -> None:
        pass

    def share_nodes(self, *node_arrays) -> None:
        pass

    def migrate(self, particles, step: int) -> int:
        return UNCHANGED

    def barrier(self) -> None:
        pass

    def fail(self, error: Exception) -> None:
        raise error

    def stop_if_failed(self) -> None:
        pass

    def sum(self, value):
        return value

    def max(self, value):
        return value

    def min(self, value):
        return value

    def any(self, flag: bool) -> bool:
        return bool(flag)

    def allgather(self, array):
        return array

    def root_says(self, flag: bool) -> bool:
        return flag

    def gather(self, fields: dict):
        return fields

    def writer(self, out_dir, scene, version: str):
        return ResultWriter(out_dir, scene, version)
