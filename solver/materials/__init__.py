"""Constitutive models, registered by the scene's `model` name.

A material is declared in one module, solver/materials/<name>.py (numba-free:
the scene schema imports it): a `MaterialType` with the pydantic model of its
scene entry (keys, validation, wave speed), its per-particle state (what it
starts at, which of it is an output field) and its solver class, named as
"module:Class" in solver/materials/kernels/ when it has numba kernels. The
scene's `materials` union, `capabilities.MATERIAL_MODELS` and the output fields
are built from the registry, so a material from elsewhere is one
`register(MaterialType(...))` (`registered(...)` for the length of a block).

The solver class turns the kinematics of its particles (L, F, volume) into
Cauchy stress:

    Model(config, dimension)             config: the scene's material entry
    .wave_speed                          dilatational wave speed for the time step
    .update_stress(particles, sl, dt)    sl: slice of the particles made of it
    .particle_strain_energy(particles, sl)  stored energy of each of those particles
    .strain_energy(particles, sl)        their sum
    .init_particles(particles, sl, scene)   optional: set what else the model needs
                                         from the bodies (a gas's initial stress)

`wave_speed` may change as the state does (a gas's sound speed, an EOS stiffening
under compression): the time step reads its current value.

Particles are sorted by material, so each model works on one contiguous slice.
"""
from __future__ import annotations

from importlib import import_module

from solver import capabilities
from solver.materials.registry import (
    REGISTRY,
    MaterialType,
    StateVariable,
    create,
    init_particles,
    names,
    on_change,
    output_fields,
    register,
    registered,
    state_values,
    unregister,
)

__all__ = ["REGISTRY", "MaterialType", "StateVariable", "create", "init_particles", "names", "on_change",
           "output_fields", "register", "registered", "state_values", "unregister", "BUILTIN"]

# The materials of this package, in the order the scene's union lists them
# (error messages name the models in this order).
BUILTIN = ("linear_elastic", "neo_hookean", "j2_plasticity", "johnson_cook", "drucker_prager", "mohr_coulomb",
           "modified_cam_clay", "fluid", "ideal_gas", "rigid")

capabilities.MATERIAL_MODELS.read_from(names)
capabilities.OUTPUT_FIELDS.read_from(capabilities.with_scene_fields(output_fields))

for _name in BUILTIN:
    register(import_module(f"solver.materials.{_name}").MATERIAL)
