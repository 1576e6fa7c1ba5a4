"""Constitutive models, registered by the scene's `model` name.

A material turns the kinematics of its particles (L, F, volume) into Cauchy
stress. Each model is one module with a class offering:

    Model(config, dimension)             config: the scene's material entry
    .wave_speed                          dilatational wave speed for the time step
    .update_stress(particles, sl, dt)    sl: slice of the particles made of it
    .particle_strain_energy(particles, sl)  stored energy of each of those particles
    .init_particles(particles, sl, scene)   optional: allocate the per-particle state the
                                         model needs (particles.require) and set it from
                                         the bodies (a gas's e and p, a temperature)

`wave_speed` may change as the state does (a gas's sound speed, an EOS stiffening
under compression): the time step reads its current value.

Particles are sorted by material, so each model works on one contiguous slice.
"""
from __future__ import annotations

from solver.materials.kernels.fluid import Fluid
from solver.materials.kernels.ideal_gas import IdealGas
from solver.materials.kernels.j2_plasticity import J2Plasticity
from solver.materials.kernels.johnson_cook import JohnsonCook
from solver.materials.kernels.linear_elastic import LinearElastic
from solver.materials.kernels.neo_hookean import NeoHookean
from solver.materials.kernels.rigid import Rigid

REGISTRY = {
    "linear_elastic": LinearElastic,
    "neo_hookean": NeoHookean,
    "fluid": Fluid,
    "ideal_gas": IdealGas,
    "rigid": Rigid,
    "j2_plasticity": J2Plasticity,
    "johnson_cook": JohnsonCook,
}


def create(config, dimension: int):
    try:
        model = REGISTRY[config.model]
    except KeyError:
        raise ValueError(f"material model {config.model!r} is not implemented; known: {sorted(REGISTRY)}") from None
    return model(config, dimension)


def init_particles(models, particles, scene) -> None:
    """Let each model allocate and set the per-particle state it needs."""
    for model, sl in models:
        init = getattr(model, "init_particles", None)
        if init is not None:
            init(particles, sl, scene)
