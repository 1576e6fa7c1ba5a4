#!/usr/bin/env python3
"""Draw docs/images/step_phases.png: the phases and hook points of each scheme, as
the code runs them (one step of a small scene per scheme, every phase and hook
call recorded), so the picture cannot drift from the step.

    .venv/bin/python scripts/step_diagram.py
"""
from __future__ import annotations

import sys
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from solver.scene_checks import load_scene  # noqa: E402
from solver.step.hooks import POINTS  # noqa: E402
from solver.stepper import ExplicitMPM  # noqa: E402

PHASES = ("weights", "particles_to_grid", "mass_momentum_to_grid", "forces_to_grid", "grid_velocities",
          "current_velocities", "remapped_velocities", "grid_to_particles", "kinematics", "stress")
LABELS = {
    "weights": "weights  phi_I(x_p)", "particles_to_grid": "P2G  m_I, (mv)_I, f_I",
    "mass_momentum_to_grid": "P2G  m_I, (mv)_I", "forces_to_grid": "P2G  f_I",
    "grid_velocities": "grid  v_I^t, v~_I^{t+dt}", "current_velocities": "grid  v_I^t",
    "remapped_velocities": "grid  v_I^{t+dt} (remap)", "grid_to_particles": "G2P  v_p, x_p",
    "kinematics": "kinematics  L_p, F_p, V_p", "stress": "stress  sigma_p",
}
SCENE = {
    "name": "diagram", "dimension": 2, "grid": {"lower": [0.0, 0.0], "upper": [1.0, 1.0], "cell_size": 0.1},
    "materials": {"m": {"model": "linear_elastic", "density": 1000, "youngs_modulus": 1e5, "poisson_ratio": 0.3}},
    "bodies": [{"name": "b", "material": "m", "geometry": {"type": "box", "lower": [0.3, 0.3], "upper": [0.6, 0.6]}}],
    "time": {"end": 1.0, "dt": 1e-3},
}


class _Trace:
    """Records the phases a scheme calls and the hook points the step passes."""

    def __init__(self, sim):
        self.sim, self.events = sim, []
        for name in PHASES:
            original = getattr(sim.phases, name)
            setattr(sim.phases, name, self._wrap(name, original))
        for point in POINTS:
            if point != "constrain":
                getattr(sim.hooks, point).append(lambda *args, point=point: self.events.append(("hook", point)))
        sim.hooks.constrain.append(self._constrain)

    def _wrap(self, name, original):
        def call(*args, **kwargs):
            self.events.append(("phase", name))
            return original(*args, **kwargs)
        return call

    def _constrain(self, grid_mass, v, record):
        which = "v_I^t" if v is self.sim.grid.v_old else "v~_I^{t+dt}" if record else "v_I^{t+dt}"
        self.events.append(("hook", f"constrain {which}"))
        return 0.0


def trace(scheme: str) -> list[tuple[str, str]]:
    sim = ExplicitMPM(load_scene({**SCENE, "method": {"scheme": scheme}}), general=True)
    recorder = _Trace(sim)
    sim.advance(1e-3)
    return recorder.events


def draw(path: Path) -> None:
    schemes = ("usl", "musl", "usf")
    columns = {s: trace(s) for s in schemes}
    rows = max(len(events) for events in columns.values())
    fig, ax = plt.subplots(figsize=(13, 0.42 * rows + 1.2))
    for c, scheme in enumerate(schemes):
        x = c * 4.4
        ax.text(x + 1.6, 0.2, scheme.upper(), ha="center", fontsize=13, weight="bold")
        for r, (kind, name) in enumerate(columns[scheme], start=1):
            y = -r * 0.9
            if kind == "phase":
                ax.add_patch(plt.Rectangle((x, y - 0.32), 3.2, 0.64, facecolor="#dbe9f6", edgecolor="#2b6cb0"))
                ax.text(x + 1.6, y, LABELS[name], ha="center", va="center", fontsize=9)
            else:
                ax.plot([x + 0.15], [y], marker="D", color="#c05621", markersize=6)
                ax.text(x + 0.4, y, f"hook: {name}", va="center", fontsize=8.5, color="#c05621", style="italic")
    ax.set_xlim(-0.3, 13.2)
    ax.set_ylim(-(rows + 1) * 0.9, 0.8)
    ax.axis("off")
    ax.set_title("One explicit step: the phases each scheme calls (boxes, solver/step/schemes.py) and the hook "
                 "points it passes (diamonds, solver/step/hooks.py)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


if __name__ == "__main__":
    out = ROOT / "docs" / "images" / "step_phases.png"
    draw(out)
    print(f"wrote {out}")
