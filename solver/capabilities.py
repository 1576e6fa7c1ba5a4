"""What the solver implements today.

The scene schema (solver/scene.py) describes the whole contract of SCENE.md; a
feature listed there but not here is rejected at validation with a
"not supported yet" error naming the field. An issue that implements a feature
adds it here in the same change, or, for materials, shape functions and output
fields, registers it: those three sets are the registries' names
(solver.materials, solver.shape, solver.fields), read each time they are used.
"""

from collections.abc import Callable, Iterable, Iterator, Set

FORMULATIONS = frozenset({"ulmpm", "tlmpm"})
SCHEMES = frozenset({"musl", "usl", "usf"})
TRANSFERS = frozenset({"flip", "pic", "apic", "mls"})
GEOMETRIES = frozenset({"box", "sphere", "cylinder", "polygon", "mesh", "points", "union", "difference", "intersection"})
BOUNDARY_CONDITIONS = frozenset({"velocity", "wall", "temperature", "heat_flux", "convection", "absorbing", "pore_pressure"})
WALL_MODES = frozenset({"stick", "slip", "friction"})
CONTACT_MODELS = frozenset({"single_field", "friction"})   # solver/contact.py
CONTACT_NORMALS = frozenset({"mass_gradient", "density_gradient"})
MAX_CONTACT_FIELD_BYTES = 16 * 2**30   # the per-body grid fields of contact "friction"
AXISYMMETRIC = True
MAX_PROCESSES = 64   # MPI ranks (solver/parallel); the service caps jobs further (MPM_MAX_PROCESSES)


class RegisteredNames(Set):
    """The current names of a registry, as a read-only set (`in`, `|`, `-` give frozensets).

    A live view rather than a frozenset taken at import: a material registered later
    is supported at once. Tests replace it with a plain set to simulate a feature
    that is not supported yet; monkeypatch puts this view back afterwards."""

    def __init__(self, names: Callable[[], Iterable[str]]):
        self._names = names

    def __contains__(self, name: object) -> bool:
        return name in frozenset(self._names())

    def __iter__(self) -> Iterator[str]:
        return iter(tuple(self._names()))

    def __len__(self) -> int:
        return len(frozenset(self._names()))

    @classmethod
    def _from_iterable(cls, names: Iterable[str]) -> frozenset[str]:
        return frozenset(names)

    def __repr__(self) -> str:
        return f"RegisteredNames({sorted(self)})"


# The registries import the scene's building blocks (solver/schema.py), which read
# this module: they are imported when a set is read, not here.

def _material_models() -> Iterable[str]:
    from solver import materials
    return materials.names()


def _shape_functions() -> Iterable[str]:
    from solver import shape
    return shape.REGISTRY


def _output_fields() -> Iterable[str]:
    from solver import fields
    return fields.names()


MATERIAL_MODELS = RegisteredNames(_material_models)
SHAPE_FUNCTIONS = RegisteredNames(_shape_functions)
# Output fields the solver can write per particle (id, body and mass are always written).
OUTPUT_FIELDS = RegisteredNames(_output_fields)
