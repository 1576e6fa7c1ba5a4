"""What the solver implements today.

The scene schema (solver/scene.py) describes the whole contract of SCENE.md; a
feature listed there but not here is rejected at validation with a
"not supported yet" error naming the field. An issue that implements a feature
adds it here in the same change, or, for materials, shape functions and output
fields of material state, registers it: those sets are the registries' names
(solver.materials, solver.shape hand them over when imported), read each time they
are used. This module imports nothing of the solver: the schema and the registries
read it.
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
# The output fields solver/fields.py forms for every scene (its FIELDS); the materials add
# their state's. Named here, not read from solver.fields: that module forms the fields from
# the particles (solver.state, solver.seeding), which read the scene.
SCENE_FIELDS = frozenset({
    "position", "velocity", "stress", "mass", "volume", "density", "pressure", "pressure_smoothed", "von_mises",
    "velocity_magnitude", "deformation_gradient", "strain_energy_density", "heat_flux", "particle_domain",
    "pore_pressure", "effective_stress", "reference_position",
})
# Of those, the ones formed from each particle's own state alone (they read sim.particles): a
# frame forms them a block of ROW_BLOCK rows at a time (solver/fields.py FrameFields.blocks), and
# the memory estimate counts a block (64 Ki rows: the stress's block is 3 MiB).
ROW_LOCAL_FIELDS = frozenset({"stress", "effective_stress", "density", "pressure", "von_mises", "velocity_magnitude"})
ROW_BLOCK = 1 << 16


class RegisteredNames(Set):
    """The current names of a registry, as a read-only set (`in`, `|`, `-` give frozensets).

    The registry that owns the names (solver.materials, solver.shape) hands over its reader
    when it is imported (`read_from`): this module sits below the registries and imports none
    of them. A live view rather than a frozenset taken at import: a material registered later
    is supported at once. Tests replace it with a plain set to simulate a feature that is not
    supported yet; monkeypatch puts this view back afterwards."""

    def __init__(self, owner: str):
        self._owner = owner
        self._names: Callable[[], Iterable[str]] | None = None

    def read_from(self, names: Callable[[], Iterable[str]]) -> None:
        self._names = names

    def _current(self) -> tuple[str, ...]:
        if self._names is None:   # every reader of the scene imports the registries first
            raise LookupError(f"no names yet: {self._owner} gives them when it is imported")
        return tuple(self._names())

    def __contains__(self, name: object) -> bool:
        return name in frozenset(self._current())

    def __iter__(self) -> Iterator[str]:
        return iter(self._current())

    def __len__(self) -> int:
        return len(frozenset(self._current()))

    @classmethod
    def _from_iterable(cls, names: Iterable[str]) -> frozenset[str]:
        return frozenset(names)

    def __repr__(self) -> str:
        return f"RegisteredNames({sorted(self)})"


def with_scene_fields(material_fields: Callable[[], Iterable[str]]) -> Callable[[], frozenset[str]]:
    """A reader of every output field: the scene's own and the materials' state."""
    def names() -> frozenset[str]:
        outputs = frozenset(material_fields())
        taken = sorted(outputs & SCENE_FIELDS)
        if taken:   # a material's state would hide a field of every scene, or the other way round
            raise ValueError(f"material state declared as output fields that every scene has: {taken}")
        return SCENE_FIELDS | outputs
    return names


MATERIAL_MODELS = RegisteredNames("solver.materials")
SHAPE_FUNCTIONS = RegisteredNames("solver.shape")
# Output fields the solver can write per particle (id, body and mass are always written).
OUTPUT_FIELDS = RegisteredNames("solver.materials")
