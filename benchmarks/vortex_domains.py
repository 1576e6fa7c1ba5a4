"""How far the E7 vortex stretches CPDI-Q4's domains (docs/benchmarks.md, "F-bar and CPDI").

    python benchmarks/vortex_domains.py

No MPM run: each particle's seeded quadrilateral is moved by the exact motion of E7
(solver/manufactured.py, which tracked corners follow up to the discretisation error)
for t in [0, 1] (41 instants; the twist peaks at t = 0.5 and undoes itself by t = 1).
Printed per h and particles_per_cell: the largest extent of a domain in cells per axis,
and the first instant at which a corner leaves today's stencil (the particle's cell and
the next one either side). With each corner in its own cell (the review's CPDI), a node
strictly inside a domain gets no weight (a hole) only where the extent exceeds 2 cells.
"""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from solver.manufactured import Options, vortex_displacement, vortex_scene  # noqa: E402
from solver.scene_checks import load_scene  # noqa: E402
from solver.stepper import ExplicitMPM  # noqa: E402


def extents(h: float, ppc: int) -> tuple[float, float | None]:
    scene = vortex_scene(h, Options(formulation="ulmpm", shape="cpdi_q4", ppc=ppc))
    scene["grid"].update(lower=[-1.5, -1.5], upper=[1.5, 1.5])
    sim = ExplicitMPM(load_scene(scene))
    q0, x0, lower = sim.particles.extra["domain_corners"].copy(), sim.particles.x.copy(), sim.grid.lower
    worst, first_out = 0.0, None
    for t in np.linspace(0, 1, 41):
        q = q0 + vortex_displacement(q0.reshape(-1, 2), t).reshape(q0.shape)
        x = x0 + vortex_displacement(x0, t)
        worst = max(worst, ((q.max(axis=1) - q.min(axis=1)) / h).max())
        cell, corner_cell = np.floor((x - lower) / h)[:, None, :], np.floor((q - lower) / h)
        if first_out is None and np.any((corner_cell < cell - 1) | (corner_cell > cell + 1)):
            first_out = float(t)
    return worst, first_out


if __name__ == "__main__":
    print("| h | particles per cell | largest extent (cells per axis) | first corner outside the 4-node stencil at t |")
    print("|---|---|---|---|")
    for h in (0.1, 0.05):
        for ppc in (2, 4, 6):
            worst, first_out = extents(h, ppc)
            print(f"| {h:g} | {ppc} | {worst:.2f} | {first_out if first_out is not None else 'never'} |", flush=True)
