"""The material registry: one `MaterialType` per scene `model` name.

Everything else that lists materials is built from it: the scene's `materials`
union and JSON schema (solver/scene.py), `capabilities.MATERIAL_MODELS`, the
output fields of material state (solver/fields.py) and the documentation check
(tests/unit/test_registry.py). Numba-free: the scene imports it.
"""

from __future__ import annotations

import importlib
import math
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Literal, get_args, get_origin

import numpy as np

from solver.schema import BaseMaterial


@dataclass(frozen=True)
class StateVariable:
    """A per-particle quantity a material keeps in ``Particles.extra`` (so checkpoints
    and migration between processes carry it)."""

    name: str
    fill: float = 0.0  # the value on particles of other materials, and of the output field there
    output: bool = False  # also written as the output field `name`
    tail: tuple[int, ...] = ()  # its shape per particle
    # (config, scene, body index of each particle of the material) -> start values; None: `fill`
    initial: Callable[[Any, Any, np.ndarray], Any] | None = None
    # allocated only for the configs where this is true (a model's optional parts); None: always
    when: Callable[[Any], bool] | None = None


@dataclass(frozen=True)
class MaterialType:
    """One material model, declared in one place.

    schema: the pydantic model of its scene entry (a ``BaseMaterial``); its
        ``model: Literal["<name>"]`` names it, its ``dilatational_wave_speed()`` and
        ``initial_wave_speed(body)`` give the summary's time step estimate.
    solver_class: what updates the stress: ``Model(config, dimension)`` with
        ``wave_speed``, ``update_stress(particles, sl, dt)``, ``particle_strain_energy
        (particles, sl)``, ``strain_energy(particles, sl)`` and optionally
        ``init_particles(particles, sl, scene)``; or "module:Class", imported when a
        run first creates it (kernels must not load with the scene).
    state: the per-particle state it keeps; those with ``output`` are output fields.
    """

    schema: type[BaseMaterial]
    solver_class: type | str
    state: tuple[StateVariable, ...] = ()

    @property
    def name(self) -> str:
        return _literal_name(self.schema)

    def outputs(self) -> dict[str, float]:
        """The output fields it provides: name -> value on other materials' particles."""
        return {variable.name: variable.fill for variable in self.state if variable.output}

    def load_solver_class(self) -> type:
        if not isinstance(self.solver_class, str):
            return self.solver_class
        module, _, name = self.solver_class.partition(":")
        return getattr(importlib.import_module(module), name)


def _literal_name(schema: type) -> str:
    field = schema.model_fields.get("model")
    args = get_args(field.annotation) if field is not None else ()
    if field is None or get_origin(field.annotation) is not Literal or len(args) != 1 or not isinstance(args[0], str):
        raise TypeError(f"{schema.__name__} must declare model: Literal[\"<name>\"]")
    return args[0]


_TYPES: dict[str, MaterialType] = {}
_LISTENERS: list[Callable[[], None]] = []

REGISTRY = MappingProxyType(_TYPES)  # name -> MaterialType, in registration order; change it with register


def register(material: MaterialType) -> MaterialType:
    """Add a material model; the scene accepts it (and its JSON schema shows it) from now on."""
    if not (isinstance(material.schema, type) and issubclass(material.schema, BaseMaterial)):
        raise TypeError(f"the schema of a material must subclass solver.schema.BaseMaterial, not {material.schema!r}")
    name = material.name
    if name in _TYPES:
        raise ValueError(f"material model {name!r} is already registered")
    _check_state(material)
    _TYPES[name] = material
    _changed()
    return material


def unregister(name: str) -> MaterialType:
    """Remove a material model (the scene rejects it again)."""
    material = _TYPES.pop(name)
    _changed()
    return material


@contextmanager
def registered(*materials: MaterialType) -> Iterator[None]:
    """The materials registered inside the block only (tests: nothing leaks into others)."""
    done = []
    try:
        for material in materials:
            done.append(register(material).name)
        yield
    finally:
        for name in reversed(done):
            unregister(name)


def on_change(listener: Callable[[], None]) -> None:
    """Call `listener()` after every registration and removal (the scene rebuilds its union)."""
    _LISTENERS.append(listener)


def _changed() -> None:
    for listener in _LISTENERS:
        listener()


def _check_state(material: MaterialType) -> None:
    """A state variable of several materials is one array: they must agree on its
    shape, its fill (the value every other particle has) and whether it is written."""
    for variable in material.state:
        for other in _TYPES.values():
            for known in other.state:
                if known.name == variable.name and not _same_array(known, variable):
                    raise ValueError(f"{material.name}: state {variable.name!r} differs from that of {other.name}")


def _same_array(a: StateVariable, b: StateVariable) -> bool:
    same_fill = a.fill == b.fill or (np.isnan(a.fill) and np.isnan(b.fill))
    return same_fill and a.tail == b.tail and a.output == b.output


def names() -> tuple[str, ...]:
    return tuple(_TYPES)


def output_fields() -> dict[str, float]:
    """Every material's output fields: name -> value on particles of materials without it."""
    out: dict[str, float] = {}
    for material in _TYPES.values():
        out.update(material.outputs())
    return out


def create(config, dimension: int):
    """The solver object of a material entry of the scene."""
    try:
        material = _TYPES[config.model]
    except KeyError:
        raise ValueError(f"material model {config.model!r} is not implemented; known: {sorted(_TYPES)}") from None
    model = material.load_solver_class()(config, dimension)
    model.config = config   # init_particles finds the declared state through it
    return model


def state_values(scene) -> int:
    """8-byte values per particle of the state the scene's materials declare (init_particles
    allocates each name once, for every particle): what solver.summary's memory estimate counts."""
    tails = {}
    for config in scene.materials.values():
        for variable in _TYPES[config.model].state:
            if variable.when is None or variable.when(config):
                tails[variable.name] = variable.tail
    return sum(math.prod(tail) for tail in tails.values())


def init_particles(models, particles, scene) -> None:
    """Allocate each model's declared state, set it on its particles, then let the
    model set what else it needs (``init_particles``: a gas's initial stress)."""
    for model, sl in models:
        config = model.config
        for variable in _TYPES[config.model].state:
            if variable.when is not None and not variable.when(config):
                continue
            values = particles.require(variable.name, variable.tail, variable.fill)
            if variable.initial is not None:
                values[sl] = variable.initial(config, scene, particles.body[sl])
        init = getattr(model, "init_particles", None)
        if init is not None:
            init(particles, sl, scene)
