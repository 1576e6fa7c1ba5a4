"""The surface particles of a body, from its seeding lattice.

Particles are seeded on a lattice of spacing s_a = h_a / ppc per axis
(solver/seeding.py). A particle is on the surface where one of its 2 dim lattice
neighbours (+-s_a e_a) is not a particle of the same body; each missing neighbour
is one lattice face of the particle, of area V_p / s_a (a length in 2D), facing
that way. So:

  area vector  a_p = sum over the missing faces of +-e_a V_p / s_a   (outward)
  area         A_p = max over the missing faces of V_p / s_a

A traction t then puts f_p = t A_p on the particle: exact on faces along the grid
axes (a corner particle counts once, so a box face's particles carry its length
or area exactly); on a curved surface the staircase's particles carry between
1/sqrt(2) and 1 of the true area (a circle: about 0.90 on average). The area
vectors of a closed body sum to zero exactly (every lattice row has as many +
faces as - faces), so a uniform pressure -p a_p has no net force.

The lattice is that of the particles at seeding (their positions before the
first step); found once, at the start of the run.
"""
from __future__ import annotations

import numpy as np


def lattice_faces(positions: np.ndarray, lower, spacing) -> np.ndarray:
    """(n, dim, 2) booleans: is the lattice neighbour of each particle at -s_a e_a
    (index 0) and +s_a e_a (index 1) missing. `positions` are one body's particles on
    the lattice lower + (k + 1/2) spacing."""
    n, dim = positions.shape
    k = np.rint((positions - np.asarray(lower)) / np.asarray(spacing) - 0.5).astype(np.int64)
    k -= k.min(axis=0) - 1 if n else 0   # >= 1: every neighbour index is >= 0
    extent = k.max(axis=0) + 2 if n else np.ones(dim, dtype=np.int64)
    strides = np.cumprod(np.r_[1, extent[:-1]])
    keys = k @ strides
    present = np.sort(keys)
    missing = np.zeros((n, dim, 2), dtype=bool)
    for a in range(dim):
        for side, step in enumerate((-1, 1)):
            wanted = keys + step * strides[a]
            at = np.minimum(np.searchsorted(present, wanted), max(n - 1, 0))
            missing[:, a, side] = present[at] != wanted
    return missing


def surface_areas(positions: np.ndarray, volume: np.ndarray, lower, spacing) -> tuple[np.ndarray, np.ndarray]:
    """(a_p (n, dim) outward area vectors, A_p (n,) areas) of one body's particles:
    zero for the particles inside."""
    missing = lattice_faces(positions, lower, spacing)
    face = volume[:, None] / np.asarray(spacing, dtype=np.float64)[None, :]   # V_p / s_a
    vector = face * (missing[:, :, 1].astype(np.float64) - missing[:, :, 0])
    area = np.max(np.where(missing.any(axis=2), face, 0.0), axis=1)
    return vector, area


def body_spacing(scene, body) -> np.ndarray:
    """The seeding lattice spacing s_a = h_a / ppc of a body."""
    return np.asarray(scene.cell_sizes(), dtype=np.float64) / body.particles_per_cell
