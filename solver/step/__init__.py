"""The explicit MPM step: schemes written once over phases, with hooks for physics.

    scheme (schemes.py)          usl / musl / usf: the order of the phases
      |  calls
    phases (phases.py)           P2G, grid update, G2P, kinematics, stress; the halo
      |  particle phases from       |  named hook points
    backend                      hooks (hooks.py)
      general.py: stored stencil    rigid bodies, boundary conditions, hoop terms,
      fused.py: weights recomputed  work of the loads; later contact, heat, damping
      |  positions, stress measure, kinematics from
    formulation (formulation.py) ULMPM / TLMPM

docs/internals.md draws the phases and the hook points of each scheme.
"""
from __future__ import annotations

from solver.step.formulation import FORMULATIONS
from solver.step.fused import FusedPhases
from solver.step.general import GeneralPhases
from solver.step.hooks import HOOKS, POINTS, Hooks, scene_hooks
from solver.step.schemes import SCHEMES

# Backends in order of preference: a scene steps with the first that supports it.
BACKENDS = (FusedPhases, GeneralPhases)


def backend_for(scene, general: bool = False):
    """The backend class a scene steps with; `general` forces the stored-stencil kernels."""
    if general:
        return GeneralPhases
    return next(backend for backend in BACKENDS if backend.supports(scene))


__all__ = ["BACKENDS", "FORMULATIONS", "HOOKS", "POINTS", "SCHEMES", "Hooks", "backend_for", "scene_hooks",
           "FusedPhases", "GeneralPhases"]
