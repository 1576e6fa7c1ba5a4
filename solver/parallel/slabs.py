"""Slabs of the grid, one per process: which cells, nodes and particles each owns.

The grid is cut along its longest axis (the one with the most cells) into K
slabs of whole cell layers (Karamelo 3.5, MPM3DMP 4.1). Slab r owns the cells
[cuts[r], cuts[r+1]) and the particles in them, and the node layers
[cuts[r], cuts[r+1]) (the last slab also the closing layer). A particle in cell
layer i touches the node layers i - (S-1)//2 ... i + ceil(S/2) of a centred
stencil S nodes wide (S = the shape function's SUPPORT: linear 2, GIMP and
quadratic B-splines 3, cubic B-splines 4), so the process of slab r keeps the
node layers [cuts[r] - (S-1)//2, cuts[r+1] + ceil(S/2)): its own and the ghost
layers of its neighbours. Plain numpy: no MPI.
"""
from __future__ import annotations

import numpy as np


def split_axis(cells) -> int:
    """The axis with the most cells; ties go to the last such axis, whose layers are contiguous in memory."""
    cells = list(cells)
    return max(range(len(cells)), key=lambda a: (cells[a], a))


def ghost_layers(support: int) -> tuple[int, int]:
    """Node layers a stencil S nodes wide reaches below and above the cell layer of its particle."""
    return (support - 1) // 2, (support + 1) // 2


def even_cuts(n_cells: int, k: int) -> np.ndarray:
    """K slabs of (nearly) equal width: the geometric split."""
    return np.array([(r * n_cells) // k for r in range(k + 1)], dtype=np.int64)


def balanced_cuts(per_layer: np.ndarray, k: int) -> np.ndarray:
    """Cuts giving each slab about the same load, each at least one layer wide.

    per_layer[i] is the load of cell layer i (its particles, or their measured work). Cut r
    goes to the layer boundary where the running load is closest to r/K of the total.
    """
    n_cells = per_layer.size
    if per_layer.sum() == 0:
        return even_cuts(n_cells, k)
    running = np.concatenate(([0], np.cumsum(per_layer)))   # particles below each layer boundary
    cuts = np.empty(k + 1, dtype=np.int64)
    cuts[0], cuts[k] = 0, n_cells
    for r in range(1, k):
        target = running[-1] * r / k
        best = int(np.argmin(np.abs(running - target)))
        cuts[r] = min(max(best, cuts[r - 1] + 1), n_cells - (k - r))   # every slab keeps a layer
    return cuts


def owned_nodes(cuts: np.ndarray, r: int) -> tuple[int, int]:
    """Node layers [lo, hi) owned by slab r: its cells' lower layers, and the closing layer for the last."""
    last = r == cuts.size - 2
    return int(cuts[r]), int(cuts[r + 1]) + (1 if last else 0)


def local_nodes(cuts: np.ndarray, r: int, support: int) -> tuple[int, int]:
    """Node layers [lo, hi) that particles of slab r touch: owned plus ghosts, within the grid."""
    below, above = ghost_layers(support)
    return max(0, int(cuts[r]) - below), min(int(cuts[-1]) + 1, int(cuts[r + 1]) + above)


def overlap(a: tuple[int, int], b: tuple[int, int]) -> tuple[int, int] | None:
    lo, hi = max(a[0], b[0]), min(a[1], b[1])
    return (lo, hi) if lo < hi else None


def layers_of(x_axis: np.ndarray, lower: float, h: float, n_cells: int) -> np.ndarray:
    """Cell layer of each position along the split axis, clipped into the grid."""
    return np.clip(np.floor((x_axis - lower) / h), 0, n_cells - 1).astype(np.int64)


def scene_problems(scene) -> list[tuple[str, str]]:
    """Validation: every process needs at least one cell layer to own; the work is balanced
    only where slabs move (ULMPM)."""
    k = scene.parallel.processes
    cells = scene.grid_shape()
    problems = []
    if k > 1 and k > max(cells):
        problems.append(("parallel.processes", f"{k} processes need at least {k} cells along the longest grid "
                                               f"axis (the grid has {max(cells)})"))
    if scene.parallel.balance == "work" and scene.method.formulation == "tlmpm":
        problems.append(("parallel.balance", "'work' needs formulation 'ulmpm': TLMPM's slabs of the reference "
                                             "configuration are balanced once, at the start"))
    return problems
