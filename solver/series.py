"""Time series a scene may ask for beside the energies (`output.series`), registered by name.

Each is a function of the simulation that gives the columns of one series row,
summed over the processes:

  momentum         momentum_<body>_<axis> = sum_p m_p v_p over each body with mass
  center_of_mass   center_of_mass_<body>_<axis> = sum_p m_p x_p / sum_p m_p, the same bodies
  reactions        reaction_bc<i>_<axis>: the mean force of the material on boundary_conditions[i]
                   since the last row (solver/boundary.py)

Rigid bodies carry no mass (they are moving boundary conditions): their reactions,
reaction_<body>_<axis>, are always written (solver/rigid.py), and their motion is the
one prescribed. A new series is a function here and an entry in SERIES.
"""
from __future__ import annotations

from typing import Callable

import numpy as np

# Rows of the energy series when `output.energies` is true: every step up to this many
# (solver/runner.py thins them out past it; solver/summary.py counts their memory).
MAX_SERIES_POINTS = 20_000

AXES = "xyz"


def _per_body(sim, weights: np.ndarray) -> np.ndarray:
    """sum over each body's particles of `weights` ((n,) or (n, dim)), summed over the processes."""
    p = sim.particles
    bodies = len(sim.scene.bodies)
    if weights.ndim == 1:
        return sim.domain.sum(np.bincount(p.body, weights=weights, minlength=bodies))
    return sim.domain.sum(np.stack([np.bincount(p.body, weights=weights[:, a], minlength=bodies)
                                    for a in range(weights.shape[1])], axis=1))


def _body_names(sim) -> list[str]:
    return [body.name.replace("/", "_") for body in sim.scene.bodies]


def momentum(sim) -> dict[str, float]:
    p = sim.particles
    mass = _per_body(sim, p.mass)
    total = _per_body(sim, p.mass[:, None] * p.v)
    return {f"momentum_{name}_{AXES[a]}": float(total[b, a])
            for b, name in enumerate(_body_names(sim)) if mass[b] > 0 for a in range(total.shape[1])}


def center_of_mass(sim) -> dict[str, float]:
    p = sim.particles
    mass = _per_body(sim, p.mass)
    moment = _per_body(sim, p.mass[:, None] * p.x)
    return {f"center_of_mass_{name}_{AXES[a]}": float(moment[b, a] / mass[b])
            for b, name in enumerate(_body_names(sim)) if mass[b] > 0 for a in range(moment.shape[1])}


def reactions(sim) -> dict[str, float]:
    return sim.condition_reactions.reactions(sim.domain)


SERIES: dict[str, Callable] = {"momentum": momentum, "center_of_mass": center_of_mass, "reactions": reactions}


def row(sim) -> dict[str, float]:
    """The columns of the series the scene asks for."""
    out: dict[str, float] = {}
    for name in sim.scene.output.series:
        out.update(SERIES[name](sim))
    return out
