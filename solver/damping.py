"""Grid damping, a hook on the summed nodal forces before the grid update.

  local (Cundall; CB-Geo, Anura3D):  f_d = -alpha |f_I| sign(v_I), per component
  viscous:                           f_d = -c m_I v_I  (c in 1/s)

with v_I = (mv)_I / m_I and f_I the unbalanced nodal force of this step. Its work,
dt sum_I f_d . (v_I^t + v~_I^{t+dt}) / 2 with the constrained velocities (the share of
the grid update's kinetic energy change that f_d makes; zero on fixed nodes), goes
into the `damping_work` series: mostly negative, the energy taken out. (Local
damping can put a little back: near a velocity reversal sign(v_I^t) lags the
force, a known trait of its explicit form; the series counts it as it is.)
"""
from __future__ import annotations

import numpy as np
from solver.jit import njit

LOCAL, VISCOUS = 0, 1


@njit(cache=True)
def damp(mode, coefficient, mass, momentum, force, mass_cutoff, damping):
    """Add the damping force to `force` on the nodes above the mass cut-off; it also
    goes into `damping` (zero elsewhere)."""
    for i in range(mass.shape[0]):
        m = mass[i]
        for a in range(force.shape[1]):
            fd = 0.0
            if m > mass_cutoff:
                if mode == LOCAL:
                    fd = -coefficient * abs(force[i, a]) * np.sign(momentum[i, a])
                else:
                    fd = -coefficient * momentum[i, a]
            damping[i, a] = fd
            force[i, a] += fd


@njit(cache=True)
def work(dt, damping, v_old, v_new):
    """dt sum_I f_d . (v_I^t + v~_I^{t+dt}) / 2."""
    total = 0.0
    for i in range(damping.shape[0]):
        for a in range(damping.shape[1]):
            total += damping[i, a] * (v_old[i, a] + v_new[i, a])
    return 0.5 * dt * total


class Damping:
    def __init__(self, spec):
        self.mode = LOCAL if spec.type == "local" else VISCOUS
        self.coefficient = float(spec.coefficient)
        self.force = np.zeros((0, 0))   # f_d of this step, per node

    def before_update(self, sim, dt: float) -> None:
        g = sim.grid
        if self.force.shape != g.force.shape:
            self.force = np.zeros_like(g.force)
        damp(self.mode, self.coefficient, g.mass, g.momentum, g.force, sim.mass_cutoff, self.force)

    def after_g2p(self, sim, dt: float) -> None:
        """The grid velocities of this step are constrained by now (MUSL's remap comes later)."""
        sim.work.add("damping_work", work(dt, self.force, sim.grid.v_old, sim.grid.v_new))
