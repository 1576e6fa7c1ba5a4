"""Constitutive models, registered by the scene's `model` name.

A material turns the kinematics of its particles (L, F, volume) into Cauchy
stress. Each model is one module with a class offering:

    Model(config, dimension)             config: the scene's material entry
    .wave_speed                          dilatational wave speed for the time step
    .update_stress(particles, sl, dt)    sl: slice of the particles made of it
    .particle_strain_energy(particles, sl)  stored energy of each of those particles
    .start(scene, particles, sl)          optional: initial state the bodies give (a gas's e, p)

`wave_speed` may change as the state does (a gas's sound speed): the time step
reads it after every stress update.

Particles are sorted by material, so each model works on one contiguous slice.
"""
from __future__ import annotations

from solver.materials.fluid import Fluid
from solver.materials.ideal_gas import IdealGas
from solver.materials.linear_elastic import LinearElastic
from solver.materials.neo_hookean import NeoHookean

REGISTRY = {
    "linear_elastic": LinearElastic,
    "neo_hookean": NeoHookean,
    "fluid": Fluid,
    "ideal_gas": IdealGas,
}


def create(config, dimension: int):
    try:
        model = REGISTRY[config.model]
    except KeyError:
        raise ValueError(f"material model {config.model!r} is not implemented; known: {sorted(REGISTRY)}") from None
    return model(config, dimension)


