"""The explicit schemes, each written once over the phases (solver/step/phases.py)
for every formulation and backend. Line numbers are those of Algorithm 1 (MUSL) of
the Karamelo paper, which is Algorithm 2 of the MPM review; the schemes differ in
when the stress is updated and from which grid velocity (review 2.5.2).
"""
from __future__ import annotations


def usl(step, dt: float) -> None:
    """Update stress last, from v~_I^{t+dt} (no remap)."""
    step.weights()                                          # phi_I(x_p), grad phi_I(x_p)
    step.particles_to_grid(dt)                              # lines 8-12: m_I, (mv)_I, f_I
    step.grid_velocities(dt)                                # lines 14-17: v_I^t, v~_I^{t+dt}
    step.grid_to_particles(dt, remap=False, kinematics=True)   # lines 18-19, 25-27: v_p, x_p; L, F, V
    step.stress(dt)                                         # line 28


def musl(step, dt: float) -> None:
    """Modified update stress last: the particles' new momentum is mapped back to the
    grid and the stress is updated from that velocity."""
    step.weights()                                          # phi_I(x_p), grad phi_I(x_p)
    step.particles_to_grid(dt)                              # lines 8-12: m_I, (mv)_I, f_I
    step.grid_velocities(dt)                                # lines 14-17: v_I^t, v~_I^{t+dt}
    step.grid_to_particles(dt, remap=True)                  # lines 18-20: v_p, x_p; (mv)_I again
    step.remapped_velocities()                              # lines 21, 24: v_I^{t+dt}
    step.kinematics(dt, step.sim.grid.v_new)                # lines 25-27: L_p, F_p, V_p
    step.stress(dt)                                         # line 28


def usf(step, dt: float) -> None:
    """Update stress first, from v_I^t, then the forces of the new stress move the grid."""
    step.weights()                                          # phi_I(x_p), grad phi_I(x_p)
    step.mass_momentum_to_grid()                            # m_I, (mv)_I
    step.current_velocities()                               # v_I^t
    step.kinematics(dt, step.sim.grid.v_old)                # L_p, F_p, V_p from v_I^t
    step.stress(dt)                                         # sigma_p
    step.forces_to_grid()                                   # f_I from the new stress
    step.grid_velocities(dt)                                # v_I^t, v~_I^{t+dt}
    step.grid_to_particles(dt, remap=False)                 # v_p, x_p


SCHEMES = {"usl": usl, "musl": musl, "usf": usf}
