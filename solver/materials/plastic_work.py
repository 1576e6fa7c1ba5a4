"""The work of plastic flow, a per-particle state of the plastic models (J2, Johnson-Cook,
Drucker-Prager, Mohr-Coulomb) and a term of the energy balance (solver/energy.py).

Each return mapping adds, per particle and step,

    d W_p = V_p sigma_{n+1} : d eps_p,    d eps_p = C^-1 : (sigma_trial - sigma_{n+1}),

the work of the step's plastic strain at the returned stress (J: the energy the material
dissipates, plus what hardening stores, since t = 0). For the radial returns (J2,
Johnson-Cook) it is q_{n+1} d eps_p_bar V_p, the Taylor-Quinney heat's sigma_f d eps_p.
Why the returned stress, not the mid-point of the return ((sigma_trial + sigma_{n+1}) / 2):
the return is backward Euler, its flow direction is that at n + 1, so sigma_{n+1} : d eps_p
is the scheme's own plastic dissipation: never negative for an associated flow, and exact
for perfect plasticity (sigma_y eps_p V, whatever the step). The mid-point value is the
whole drop of the stored energy in the return; it exceeds this by
d eps_p : C : d eps_p / 2 V_p (3 G d eps_p_bar^2 / 2 V_p in J2), the backward Euler
return's numerical dissipation, which thus stays in `energy_error`, O(dt).

V_p is the particle's current volume (that of the internal force). Other materials'
particles keep 0.
"""
from __future__ import annotations

from solver.materials.registry import REGISTRY, StateVariable

NAME = "plastic_work"
STATE = StateVariable(NAME)


def present(scene) -> bool:
    """Whether a material of the scene keeps the plastic work (a column of its series)."""
    models = [REGISTRY.get(material.model) for material in scene.materials.values()]
    return any(STATE in model.state for model in models if model is not None)


def local(sim) -> float:
    """This process's particles' plastic work."""
    work = sim.particles.extra.get(NAME)
    return 0.0 if work is None else float(work.sum())
