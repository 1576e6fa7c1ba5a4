"""The scene: pydantic models of the whole contract in SCENE.md, and ``parse_scene``.

Validation happens in two passes, both reporting every problem they find:

1. the structure: types, ranges, unknown keys, expression syntax, and the rules
   that concern one part of the scene (a box's upper corner above its lower one,
   the fixed time step against ``max_steps``, features the solver does not
   implement yet);
2. once the structure is valid, the rules that tie parts together (vector lengths
   against ``dimension``, material names, bodies inside the grid, ...): solver/scene_rules.py,
   which the scene's last validator calls.

Features of the contract that the solver does not implement yet (see
``solver.capabilities``) are rejected with "... is not supported yet" at the
field's path. The capability sets are read at validation time, so implementing a
feature only edits ``capabilities.py``, or registers it.

The materials (their scene entries) and the shape functions come from their
registries (solver.materials, solver.shape); the building blocks shared with the
material declarations are in solver/schema.py. This module loads without numba.

The checks that count a scene (its size against limits, its time step against the
stability limit) read these models, and run above them: solver.scene_checks.load_scene
is what loads a scene for a run, the CLI and the service.
"""

import json
import math
from pathlib import Path
from typing import Annotated, Any, Literal, Union

import numpy as np
from pydantic import (
    Field,
    PlainValidator,
    PrivateAttr,
    Strict,
    ValidationError,
    ValidationInfo,
    field_validator,
    model_validator,
)

from solver import capabilities
from solver import materials as material_registry
from solver import shape as shape_functions
from solver import geometry as geometry_shapes
from solver import mesh as meshes
from solver import points as point_sets
from solver.errors import SolverError
from contextvars import ContextVar

from solver.expressions import ExpressionError, compile_expression, definition_problems
from solver.units import Units
from solver.schema import (
    BODY_FORCE_VARIABLES,
    DEFAULT_FRAMES,
    SPACE_VARIABLES,
    TIME_VARIABLES,
    Boolean,
    NonNegative,
    Positive,
    Real,
    MAX_COUNT,
    SceneModel,
    count_up,
    fmt,
    problems_at,
    require_supported,
    supported,
    scene_error,
)
from solver.scene_rules import cross_checks

# The scene's named expressions (`expressions`) while a scene is being validated: the
# fields read before the scene is whole (a body force naming `bx`) compile against them.
_DEFINITIONS: ContextVar[dict[str, str] | None] = ContextVar("scene_expressions", default=None)

# Every output field name of the contract; the solver writes those listed in
# capabilities.OUTPUT_FIELDS (id, body and mass are always written).
CONTRACT_OUTPUT_FIELDS = frozenset({
    "position", "velocity", "stress", "mass", "volume", "density", "pressure",
    "plastic_strain", "damage", "temperature", "velocity_magnitude", "von_mises",
    "deformation_gradient", "strain_energy_density", "pore_pressure", "effective_stress",
})


# --------------------------------------------------------------------------- errors

class SceneError(SolverError, ValueError):
    """An invalid scene. ``errors`` lists every problem as ``{"path", "message"}``."""

    def __init__(self, errors: list[dict[str, str]]):
        self.errors = errors
        super().__init__("\n".join(f"{e['path']}: {e['message']}" if e["path"] else e["message"] for e in errors))


# --------------------------------------------------------------------------- value types

def _finite_number(value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise scene_error("must be a number")
    if not math.isfinite(value):
        raise scene_error("must be a finite number")
    return float(value)


def _number_or_expression(variables: tuple[str, ...]):
    """A number, or an expression string over ``variables`` (checked when read)."""

    def validate(value: Any) -> float | str:
        if isinstance(value, str):
            try:
                compile_expression(value, variables, _DEFINITIONS.get())
            except ExpressionError as exc:
                shown = value if len(value) <= 80 else value[:60] + "..."  # not a huge input echoed
                raise scene_error(f"invalid expression {shown!r}: {exc}") from None
            return value
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise scene_error(f"must be a number or an expression string in {', '.join(variables)}")
        return _finite_number(value)

    return Annotated[Union[float, str], PlainValidator(validate, json_schema_input_type=Union[float, str])]


def _cell_size(value: Any) -> float | list[float]:
    if isinstance(value, (list, tuple)):
        if not value:
            raise scene_error("must not be empty")
        sizes = [_finite_number(v) for v in value]
        if any(size <= 0 for size in sizes):
            raise scene_error(f"every cell size must be > 0, got {value}")
        return sizes
    size = _finite_number(value)
    if size <= 0:
        raise scene_error("must be > 0")
    return size


def _energies(value: Any) -> bool | int:
    if isinstance(value, bool):
        return value
    if isinstance(value, int) and value >= 1:
        return value
    raise scene_error("must be true, false or a whole number of steps >= 1")


Vector = Annotated[list[Real], Field(min_length=1, max_length=3)]
SpaceValue = _number_or_expression(SPACE_VARIABLES)
TimeValue = _number_or_expression(TIME_VARIABLES)
BodyForceValue = _number_or_expression(BODY_FORCE_VARIABLES)
CellSize = Annotated[
    Union[float, list[float]],
    PlainValidator(_cell_size, json_schema_input_type=Union[Positive, list[Positive]]),
]
Energies = Annotated[
    Union[bool, int],
    PlainValidator(_energies, json_schema_input_type=Union[bool, Annotated[int, Field(ge=1)]]),
]


def _upper_above_lower(upper: list[float] | None, info: ValidationInfo) -> list[float] | None:
    """Field validator of ``upper`` (declared after ``lower``) in boxes and the grid."""
    lower = info.data.get("lower")
    if upper is None or lower is None:
        return upper
    if len(lower) != len(upper):
        raise scene_error(f"has {len(upper)} components but lower has {len(lower)}")
    problems = [(f"[{i}]", f"must be > lower[{i}] = {fmt(lo)}") for i, (lo, up) in enumerate(zip(lower, upper)) if not up > lo]
    if problems:
        raise problems_at(problems)
    return upper


# --------------------------------------------------------------------------- method, grid

class Method(SceneModel):
    formulation: Literal["ulmpm", "tlmpm"] = "ulmpm"
    scheme: Literal["musl", "usl", "usf"] = "musl"
    # the registered shape functions, in the registry's order (the order error messages list them)
    shape_function: Literal[tuple(shape_functions.REGISTRY)] = "linear"
    transfer: Literal["flip", "pic", "apic", "mls"] = "flip"
    flip_ratio: Annotated[float, Strict(), Field(ge=0, le=1)] = 0.99
    # F-bar (review 5.2, Algorithm 7): the stress from the cell-averaged Jacobian (solver/fbar.py)
    fbar: Annotated[bool, Strict()] = False

    _formulation_supported = supported("formulation", "FORMULATIONS")

    _scheme_supported = supported("scheme", "SCHEMES")

    @field_validator("shape_function")
    @classmethod
    def _shape_function_allowed(cls, value: str, info: ValidationInfo) -> str:
        formulation = info.data.get("formulation")
        declared = shape_functions.REGISTRY[value]
        if formulation is not None and formulation not in declared.formulations:
            raise scene_error(declared.formulation_refusal)
        return require_supported(value, "SHAPE_FUNCTIONS")

    @field_validator("transfer")
    @classmethod
    def _transfer_supported(cls, value: str, info: ValidationInfo) -> str:
        shape_function = info.data.get("shape_function")
        if value == "apic" and shape_function is not None and not shape_functions.REGISTRY[shape_function].apic:
            raise scene_error(shape_functions.REGISTRY[shape_function].apic_refusal)
        if value == "mls" and shape_function is not None and not shape_functions.REGISTRY[shape_function].smooth:
            smooth = [name for name, declared in shape_functions.REGISTRY.items() if declared.smooth]
            raise scene_error(f"'mls' needs a C1 shape function ({' or '.join(smooth)}), not "
                              f"'{shape_function}': its gradient w D_p^-1 (x_I - x_p) stands in for grad w, "
                              "which only a C1 function makes vanish where the weight does")
        return require_supported(value, "TRANSFERS")


class Grid(SceneModel):
    """The background grid. ``lower``/``upper`` may be left out only with tlmpm; the
    grid then covers the bodies' bounding box padded by two cells."""

    lower: Vector | None = None
    upper: Vector | None = None
    cell_size: CellSize

    _upper = field_validator("upper")(_upper_above_lower)


# --------------------------------------------------------------------------- materials

def _material_union() -> Any:
    """The registered materials' scene entries, told apart by their "model"."""
    schemas = tuple(material.schema for material in material_registry.REGISTRY.values())
    return Annotated[Union[schemas], Field(discriminator="model")]


Material = _material_union()


# Until the checks moved above the schema, `from solver.scene import load_scene` loaded a scene;
# the schema imports nothing that reads it back, so an old import is told where the name is now
# (an ImportError: `from ... import` would replace an AttributeError's message with its own).
_MOVED_TO_CHECKS = ("load_scene", "Limits", "MACHINE_LIMITS", "COUNT_FACTOR")


def __getattr__(name: str) -> type:
    """The registered materials' schema classes by name (solver.scene.NeoHookean, ...):
    they are declared in solver/materials/ and were defined here before the registry."""
    for material in material_registry.REGISTRY.values():
        if material.schema.__name__ == name:
            return material.schema
    if name in _MOVED_TO_CHECKS:
        raise ImportError(f"solver.scene.{name} is now solver.scene_checks.{name} "
                          f"(from solver.scene_checks import {name})", name=name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


# --------------------------------------------------------------------------- geometry

class _Geometry(SceneModel):
    @field_validator("type", check_fields=False)
    @classmethod
    def _type_supported(cls, value: str) -> str:
        return require_supported(value, "GEOMETRIES")

    def shape(self) -> geometry_shapes.Geometry:
        """The inside-test object of ``solver.geometry``."""
        return geometry_shapes.from_spec(self)


class BoxGeometry(_Geometry):
    type: Literal["box"]
    lower: Vector
    upper: Vector

    _upper = field_validator("upper")(_upper_above_lower)


class SphereGeometry(_Geometry):
    """A ball in 3D, a disk in 2D, a segment in 1D."""

    type: Literal["sphere"]
    center: Vector
    radius: Positive


class CylinderGeometry(_Geometry):
    """3D only: a circular cylinder along coordinate ``axis``, centred on ``center``."""

    type: Literal["cylinder"]
    center: Vector
    radius: Positive
    axis: Annotated[int, Strict(), Field(ge=0, le=2)] = 2
    height: Positive


class PolygonGeometry(_Geometry):
    """2D only: a simple polygon (concave allowed, either orientation), by its vertices."""

    type: Literal["polygon"]
    vertices: Annotated[list[Annotated[list[Real], Field(min_length=2, max_length=2)]],
                        Field(min_length=3, max_length=geometry_shapes.MAX_POLYGON_VERTICES)]

    @field_validator("vertices")
    @classmethod
    def _simple(cls, vertices: list[list[float]], info: ValidationInfo) -> list[list[float]]:
        # the scene's polygons together, counted as they are validated: a union of thousands
        # is refused at the one that passes the cap, before its own check runs
        seen = (info.context or {}).get("polygons")   # [polygons, vertices, refused already]
        if seen is not None:
            seen[0] += 1
            seen[1] += len(vertices)
            if seen[2]:
                return vertices   # the scene is refused at the first polygon past a cap: said once
            if seen[0] > geometry_shapes.MAX_POLYGONS or seen[1] > geometry_shapes.MAX_POLYGON_VERTICES:
                seen[2] = True
                raise scene_error(f"the scene has {seen[0]} polygons of {seen[1]} vertices so far, more than "
                                  f"{geometry_shapes.MAX_POLYGONS} polygons or {geometry_shapes.MAX_POLYGON_VERTICES}"
                                  " vertices together (each is checked, and each inside test loops over every edge)")
        try:
            crossing = geometry_shapes.first_crossing(np.array(vertices, dtype=np.float64))
        except geometry_shapes.TooComplex as exc:
            raise scene_error(f"the polygon is too complex: {exc}") from None
        if crossing is not None:
            i, j = crossing
            n = len(vertices)
            raise scene_error(f"the polygon intersects itself: edge {i} (vertices[{i}] to vertices[{(i + 1) % n}]) "
                              f"meets edge {j} (vertices[{j}] to vertices[{(j + 1) % n}])")
        return vertices


# Why a "file" cannot be read: the scene came as a document (the service's case), not as a file.
FILES_REFUSED = ("a scene sent as a document cannot name a file (the service never opens a path named in "
                 "a scene): send the file's bytes as \"data\" (base64) with its \"format\"; `mpm submit` "
                 "and the SDK inline a local file")


def files_folder(info: ValidationInfo) -> Path | None:
    """The folder a scene's relative file names start from; None where files may not be read
    (a scene validated without parse_scene's `files`, as the service does)."""
    folder = (info.context or {}).get("files")
    return None if folder is None else Path(folder)


class MeshGeometry(_Geometry):
    """3D only: a closed triangle mesh (solver/mesh.py), from a file or base64 data."""

    type: Literal["mesh"]
    file: Annotated[str, Field(min_length=1)] | None = None   # STL or OBJ; relative to the scene file
    data: str | None = None                                     # base64 of the file's bytes
    format: Literal[meshes.FORMATS] | None = None               # with data; a file's suffix otherwise
    scale: Positive = 1.0
    translate: Annotated[list[Real], Field(min_length=3, max_length=3)] = Field(default_factory=lambda: [0.0] * 3)

    _mesh: meshes.Mesh | None = PrivateAttr(None)

    @model_validator(mode="after")
    def _read(self, info: ValidationInfo) -> "MeshGeometry":
        if (self.file is None) == (self.data is None):
            raise problems_at([("file", "give either file (a path) or data (base64), not both")
                               if self.file is not None else ("data", "give file (a path) or data (base64)")])
        source, raw = ("data", None) if self.data is not None else ("file", None)
        fmt = self.format or (meshes.format_of(self.file) if self.file is not None else None)
        if fmt is None:
            raise problems_at([("format", f"required: one of {list(meshes.FORMATS)}"
                                          + (" (the file's suffix names none)" if self.file else ""))])
        limit = meshes.max_mesh_bytes()
        try:
            if self.data is not None:
                raw = meshes.decode_data(self.data, limit)
            else:
                folder = files_folder(info)
                if folder is None:
                    raise problems_at([("file", FILES_REFUSED)])
                self.file = str((folder / self.file).resolve())   # the scene can be reloaded from anywhere
                raw = meshes.read_file(self.file, limit)
            self._mesh = meshes.load(raw, fmt, self.scale, self.translate)
        except meshes.GeometryFileError as exc:
            raise problems_at([(source, str(exc))]) from None
        return self

    def shape(self) -> meshes.Mesh:
        return self._mesh


class PointsGeometry(_Geometry):
    """A body given as its particles (solver/points.py): positions and volumes, or a CSV /
    HDF5 file of them (x, y[, z], volume). Only as a body's whole geometry."""

    type: Literal["points"]
    positions: Annotated[list[Annotated[list[Real], Field(min_length=1, max_length=3)]], Field(min_length=1)] | None = None
    volumes: Annotated[list[Positive], Field(min_length=1)] | None = None
    file: Annotated[str, Field(min_length=1)] | None = None   # .csv, .h5 or .hdf5; relative to the scene file

    _points: point_sets.Points | None = PrivateAttr(None)

    @model_validator(mode="after")
    def _read(self, info: ValidationInfo) -> "PointsGeometry":
        inline = self.positions is not None or self.volumes is not None
        if inline == (self.file is not None):
            raise problems_at([("file", "give either file or positions and volumes, not both") if inline
                               else ("positions", "give positions and volumes, or file")])
        try:
            if inline:
                if self.positions is None or self.volumes is None:
                    raise problems_at([("volumes" if self.volumes is None else "positions", "required with "
                                        + ("positions" if self.volumes is None else "volumes"))])
                if len({len(p) for p in self.positions}) != 1:
                    raise problems_at([("positions", "every position needs the same number of components")])
                self._points = point_sets.from_lists(self.positions, self.volumes)
            else:
                folder = files_folder(info)
                if folder is None:
                    raise problems_at([("file", FILES_REFUSED.replace(
                        "send the file's bytes as \"data\" (base64) with its \"format\"", "send positions and volumes"))])
                self.file = str((folder / self.file).resolve())
                self._points = point_sets.from_file(self.file, meshes.max_mesh_bytes())
        except meshes.GeometryFileError as exc:
            raise problems_at([("file" if self.file else "volumes", str(exc))]) from None
        return self

    def shape(self) -> point_sets.Points:
        return self._points


class UnionGeometry(_Geometry):
    type: Literal["union"]
    parts: Annotated[list["GeometrySpec"], Field(min_length=1)]


class DifferenceGeometry(_Geometry):
    """The first part minus all the others."""

    type: Literal["difference"]
    parts: Annotated[list["GeometrySpec"], Field(min_length=1)]


class IntersectionGeometry(_Geometry):
    type: Literal["intersection"]
    parts: Annotated[list["GeometrySpec"], Field(min_length=1)]


GeometrySpec = Annotated[
    Union[BoxGeometry, SphereGeometry, CylinderGeometry, PolygonGeometry, MeshGeometry, PointsGeometry,
          UnionGeometry, DifferenceGeometry, IntersectionGeometry],
    Field(discriminator="type"),
]
for _combined in (UnionGeometry, DifferenceGeometry, IntersectionGeometry):
    _combined.model_rebuild()


# --------------------------------------------------------------------------- bodies, conditions

class GeostaticStress(SceneModel):
    """sigma_v = -rho g depth below the body's top, sigma_h = k0 sigma_v (solver/initial_stress.py)."""

    type: Literal["geostatic"]
    k0: NonNegative | None = None   # None: 1 - sin(friction_angle) of the body's material


class InitialPorePressure(SceneModel):
    """A saturated body's pore pressure at t = 0 (solver/pore_fluid.py): "hydrostatic" below
    `water_table` (a height: y in 2D, z in 3D; 0 above it) under the scene's gravity, or "uniform"."""

    type: Literal["hydrostatic", "uniform"]
    water_table: Real | None = None   # hydrostatic
    pressure: Real | None = None      # uniform, Pa (positive in compression)

    @model_validator(mode="after")
    def _keys_of_type(self) -> "InitialPorePressure":
        needed, unused = ("water_table", "pressure") if self.type == "hydrostatic" else ("pressure", "water_table")
        problems = []
        if getattr(self, needed) is None:
            problems.append((needed, f"required with type {self.type!r}"))
        if getattr(self, unused) is not None:
            problems.append((unused, f"not used with type {self.type!r}"))
        if problems:
            raise problems_at(problems)
        return self


class Body(SceneModel):
    name: Annotated[str, Field(min_length=1)]
    material: str
    geometry: GeometrySpec
    particles_per_cell: Annotated[int, Strict(), Field(ge=1, le=100)] = 2  # per axis; bounded before any allocation
    initial_velocity: list[SpaceValue] | None = None  # None: at rest
    initial_temperature: NonNegative | None = None
    initial_density: Positive | None = None  # ideal_gas bodies only
    initial_pressure: NonNegative | None = None  # ideal_gas bodies only
    velocity: list[TimeValue | None] | None = None  # rigid bodies only; None: at rest; a null component: free axis
    initial_stress: GeostaticStress | None = None   # None: stress-free
    initial_pore_pressure: InitialPorePressure | None = None   # saturated bodies; None: 0


# where a velocity condition holds: the geometries defined by numbers alone (no files)
NodeRegion = Annotated[Union[BoxGeometry, SphereGeometry, CylinderGeometry, UnionGeometry, DifferenceGeometry,
                             IntersectionGeometry], Field(discriminator="type")]


class VelocityCondition(SceneModel):
    """Grid nodes inside ``where`` get the given components; None leaves one free. ``where``
    is a box (its faces included, within round-off) or another geometry of the nodes' space
    (a disk, a ring's outside as a difference: an imported Karamelo region)."""

    type: Literal["velocity"]
    where: NodeRegion
    velocity: Annotated[list[TimeValue | None], Field(min_length=1)]

    _type_supported = supported("type", "BOUNDARY_CONDITIONS")


class WallCondition(SceneModel):
    type: Literal["wall"]
    face: Literal["x-", "x+", "y-", "y+", "z-", "z+"]
    mode: Literal["stick", "slip", "friction"]
    friction: NonNegative | None = None  # Coulomb coefficient, mode "friction" only

    _type_supported = supported("type", "BOUNDARY_CONDITIONS")

    _mode_supported = supported("mode", "WALL_MODES")

    @model_validator(mode="after")
    def _friction_with_mode(self) -> "WallCondition":
        if self.mode == "friction" and self.friction is None:
            raise problems_at([("friction", "required with mode 'friction'")])
        if self.mode != "friction" and self.friction is not None:
            raise problems_at([("friction", "only used with mode 'friction'")])
        return self


Face = Literal["x-", "x+", "y-", "y+", "z-", "z+"]


class _HeldOnNodes(SceneModel):
    """A grid field's value held on a face or on the nodes inside a box."""

    face: Face | None = None
    where: BoxGeometry | None = None

    @model_validator(mode="after")
    def _face_or_box(self) -> "_HeldOnNodes":
        if (self.face is None) == (self.where is None):
            raise scene_error("give either face or where (a box of nodes)")
        return self


class TemperatureCondition(_HeldOnNodes):
    """The grid temperature held on a face or on the nodes inside a box ([R] Algorithm 8,
    lines 10 and 14; solver/thermal.py)."""

    type: Literal["temperature"]
    temperature: TimeValue

    _type_supported = supported("type", "BOUNDARY_CONDITIONS")


class HeatFluxCondition(SceneModel):
    """A heat flux (W/m^2, positive into the body) through a face of the grid."""

    type: Literal["heat_flux"]
    face: Face
    flux: TimeValue

    _type_supported = supported("type", "BOUNDARY_CONDITIONS")


class ConvectionCondition(SceneModel):
    """Heat exchanged with the surroundings through a face: q = coefficient (ambient - T)."""

    type: Literal["convection"]
    face: Face
    coefficient: NonNegative   # W/(m^2 K)
    ambient: Real              # K

    _type_supported = supported("type", "BOUNDARY_CONDITIONS")


class PorePressureCondition(_HeldOnNodes):
    """A drained face (or box of nodes): the grid's pore pressure held there (solver/pore_fluid.py);
    faces without one are impervious."""

    type: Literal["pore_pressure"]
    pressure: TimeValue

    _type_supported = supported("type", "BOUNDARY_CONDITIONS")


class AbsorbingCondition(SceneModel):
    """Viscous (Lysmer-Kuhlemeyer) dashpots on a face of the grid (solver/absorbing.py)."""

    type: Literal["absorbing"]
    face: Face

    _type_supported = supported("type", "BOUNDARY_CONDITIONS")


BoundaryCondition = Annotated[Union[VelocityCondition, WallCondition, TemperatureCondition, HeatFluxCondition,
                                    ConvectionCondition, AbsorbingCondition, PorePressureCondition],
                              Field(discriminator="type")]


# --------------------------------------------------------------------------- loads, damping

LoadVector = Annotated[list[TimeValue], Field(min_length=1, max_length=3)]


class _Load(SceneModel):
    body: str
    where: BoxGeometry

    @property
    def vector(self) -> list[float | str]:
        """The force or traction components (the field named by the type)."""
        return getattr(self, self.type)


class ForceLoad(_Load):
    """A total force, shared by the body's particles inside ``where`` in proportion to their mass."""

    type: Literal["force"]
    force: LoadVector


class TractionLoad(_Load):
    """A force per area on the body's surface particles inside ``where`` (solver/surface.py)."""

    type: Literal["traction"]
    traction: LoadVector


Load = Annotated[Union[ForceLoad, TractionLoad], Field(discriminator="type")]


class Damping(SceneModel):
    """Grid damping: "local" (Cundall: -alpha |f_I| sign(v_I) per component, alpha in [0, 1])
    or "viscous" (-c m_I v_I, c in 1/s)."""

    type: Literal["local", "viscous"]
    coefficient: NonNegative

    @model_validator(mode="after")
    def _local_at_most_one(self) -> "Damping":
        if self.type == "local" and self.coefficient > 1:
            raise problems_at([("coefficient", "must be <= 1 for local damping (a share of the unbalanced force)")])
        return self


# --------------------------------------------------------------------------- tools

ToolGeometry = Annotated[Union[PolygonGeometry, MeshGeometry, SphereGeometry, BoxGeometry], Field(discriminator="type")]


class Tool(SceneModel):
    """A rigid obstacle moving with a prescribed velocity that pushes the particles entering
    it by a Hertz penalty (Karamelo 4.4; solver/tools.py). `stiffness` is a multiple of the
    touched material's shear modulus; `friction` is Coulomb's mu against the particles."""

    name: Annotated[str, Field(min_length=1)]
    geometry: ToolGeometry             # polygon (2D), mesh (3D), sphere, box
    velocity: Annotated[list[TimeValue], Field(min_length=1, max_length=3)] | None = None   # None: at rest
    stiffness: Positive = 1.0
    friction: NonNegative = 0.0


# --------------------------------------------------------------------------- contact

class ContactPair(SceneModel):
    """The friction of one pair of bodies (overrides the contact's `friction`)."""

    bodies: Annotated[list[str], Field(min_length=2, max_length=2)]
    friction: NonNegative


class Contact(SceneModel):
    """How bodies meet ([R] 5.1): "single_field" (one velocity field, bodies stick where
    they share nodes) or "friction" (a velocity field per body, Coulomb friction between
    them, Bardenhagen et al. 2000; solver/contact.py)."""

    model: Literal["single_field", "friction"] = "single_field"
    friction: NonNegative = 0.0   # mu of every pair the `pairs` do not list
    pairs: list[ContactPair] = Field(default_factory=list)
    normals: Literal["mass_gradient", "density_gradient"] = "mass_gradient"   # [R] (5.12) | (5.9)-(5.11)

    _model_supported = supported("model", "CONTACT_MODELS")

    _normals_supported = supported("normals", "CONTACT_NORMALS")

    @property
    def fields(self) -> bool:
        """Whether each body has a velocity field of its own."""
        return self.model != "single_field"


# --------------------------------------------------------------------------- time, output

class Time(SceneModel):
    end: Positive
    dt: Positive | None = None  # None: adaptive, dt = cfl * h / max(c + |v|)
    cfl: Annotated[float, Strict(), Field(gt=0, le=1)] = 0.5
    max_steps: Annotated[int, Strict(), Field(ge=1)] = 10_000_000
    # a fixed dt above the stability limit (solver/stability.py) is refused unless this is true
    allow_unstable_dt: Boolean = False

    def fixed_steps(self) -> int | None:
        """Steps of a fixed-dt run: end/dt rounded up, ignoring round-off below a
        millionth of a step (3.5 / 0.001 is 3500); None if adaptive."""
        if self.dt is None:
            return None
        return max(1, count_up(self.end / self.dt - 1e-6))   # 1e308 / 1e-308 is a count, not an error

    @model_validator(mode="after")
    def _steps_within_guard(self) -> "Time":
        steps = self.fixed_steps()
        if steps is not None and steps > self.max_steps:
            shown = steps if steps < MAX_COUNT else f"{self.end / self.dt:.3g}"
            raise problems_at([("dt", f"end / dt = {shown} steps, more than max_steps = {self.max_steps}")])
        return self


def _known_output_field(name: str) -> str | None:
    """None if ``name`` can be written, else the reason."""
    if name not in CONTRACT_OUTPUT_FIELDS | capabilities.OUTPUT_FIELDS:
        known = ", ".join(sorted(CONTRACT_OUTPUT_FIELDS | capabilities.OUTPUT_FIELDS))
        return f"unknown output field {name!r}; known fields: {known}"
    if name not in capabilities.OUTPUT_FIELDS:
        return f"{name!r} is not supported yet"
    return None


class Preview(SceneModel):
    field: str = "velocity_magnitude"

    @field_validator("field")
    @classmethod
    def _field_known(cls, value: str) -> str:
        reason = _known_output_field(value)
        if reason:
            raise scene_error(reason)
        return value


class Checkpoint(SceneModel):
    """Restart checkpoints (solver/checkpoint.py): every N steps and/or M seconds of wall time."""
    every_steps: Annotated[int, Strict(), Field(ge=1)] | None = None
    every_seconds: Positive | None = None

    @model_validator(mode="after")
    def _one_given(self) -> "Checkpoint":
        if self.every_steps is None and self.every_seconds is None:
            raise scene_error("give every_steps, every_seconds or both")
        return self


class Output(SceneModel):
    frames: Annotated[int, Strict(), Field(ge=2)] = DEFAULT_FRAMES  # first and last included
    fields: list[str] = Field(default_factory=lambda: ["position", "velocity", "stress"])
    energies: Energies = True  # or N: every N steps
    preview: Preview = Field(default_factory=Preview)
    checkpoint: Checkpoint | None = None  # unset: the runner's interval (every minute by default)
    # time series beside the energies, written with them (solver/series.py): momentum, center_of_mass, reactions
    series: list[str] = Field(default_factory=list)

    @field_validator("series")
    @classmethod
    def _series_known(cls, names: list[str]) -> list[str]:
        from solver.series import SERIES   # numpy only; it reads no scene model
        problems = []
        for i, name in enumerate(names):
            if name not in SERIES:
                problems.append((f"[{i}]", f"unknown series {name!r}; known series: {', '.join(SERIES)}"))
            elif name in names[:i]:
                problems.append((f"[{i}]", f"{name!r} is listed twice"))
        if problems:
            raise problems_at(problems)
        return names

    @field_validator("fields")
    @classmethod
    def _fields_known(cls, fields: list[str]) -> list[str]:
        problems = []
        for i, name in enumerate(fields):
            reason = _known_output_field(name)
            if reason:
                problems.append((f"[{i}]", reason))
            elif name in fields[:i]:
                problems.append((f"[{i}]", f"{name!r} is listed twice"))
        if problems:
            raise problems_at(problems)
        return fields


class Parallel(SceneModel):
    processes: Annotated[int, Strict(), Field(ge=1)] = 1  # a request; the service may cap it
    # slabs are balanced by particle counts at the start and every N steps; 0: even slabs, never moved
    rebalance_every: Annotated[int, Strict(), Field(ge=0)] = 100
    # what the rebalancing evens out: each slab's particles, or its measured work (the time each
    # process spent stepping, off its waits, shared out over its particles: solver/parallel/mpi.py)
    balance: Literal["particles", "work"] = "particles"
    # threads per process (solver/threads.py); 0: the cores this machine gives the run, shared among its processes
    threads: Annotated[int, Strict(), Field(ge=0, le=1024)] = 0

    @field_validator("processes")
    @classmethod
    def _processes_supported(cls, value: int) -> int:
        if value > capabilities.MAX_PROCESSES:
            raise scene_error(f"{value} processes is not supported yet (at most {capabilities.MAX_PROCESSES})")
        return value

    @model_validator(mode="after")
    def _work_is_measured_between_rebalances(self) -> "Parallel":
        if self.balance == "work" and self.rebalance_every == 0:
            raise problems_at([("balance", "'work' needs rebalance_every > 0: the work is measured between "
                                           "rebalancings, and 0 never moves the slabs")])
        return self


# --------------------------------------------------------------------------- the scene

class Scene(SceneModel):
    version: Literal[1] = 1
    name: str = "untitled"
    dimension: Literal[1, 2, 3]
    axisymmetric: Boolean = False  # 2D only: x = r, y = z
    method: Method = Field(default_factory=Method)
    grid: Grid
    materials: Annotated[dict[str, Material], Field(min_length=1)]
    bodies: Annotated[list[Body], Field(min_length=1)]
    boundary_conditions: list[BoundaryCondition] = Field(default_factory=list)
    gravity: Vector | None = None
    body_force: list[BodyForceValue] | None = None
    loads: list[Load] = Field(default_factory=list)
    damping: Damping | None = None
    contact: Contact = Field(default_factory=Contact)
    tools: list[Tool] = Field(default_factory=list)
    time: Time
    output: Output = Field(default_factory=Output)
    parallel: Parallel = Field(default_factory=Parallel)
    units: Units | None = None  # labels only (solver/units.py): plots show them, nothing is converted
    # named sub-expressions that every expression of the scene may use by name (third wave)
    expressions: dict[str, str] = Field(default_factory=dict)

    @model_validator(mode="wrap")
    @classmethod
    def _with_definitions(cls, data: Any, handler):
        """The named expressions are known while the fields that use them are read."""
        given = data.get("expressions") if isinstance(data, dict) else None
        definitions = ({k: v for k, v in given.items() if isinstance(k, str) and isinstance(v, str)}
                       if isinstance(given, dict) else None)
        token = _DEFINITIONS.set(definitions or None)
        try:
            return handler(data)
        finally:
            _DEFINITIONS.reset(token)

    @field_validator("expressions")
    @classmethod
    def _definitions_sound(cls, value: dict[str, str]) -> dict[str, str]:
        problems = definition_problems(value, BODY_FORCE_VARIABLES)
        if problems:
            raise problems_at([(name, message) for name, message in problems])
        return value

    def expression(self, text: str, variables: tuple[str, ...]):
        """An expression of this scene, compiled with its named expressions."""
        return compile_expression(text, variables, self.expressions)

    @field_validator("axisymmetric")
    @classmethod
    def _axisymmetric_in_2d(cls, value: bool, info: ValidationInfo) -> bool:
        if value and info.data.get("dimension", 2) != 2:
            raise scene_error("only possible with dimension 2 (x = r, y = z)")
        if value and not capabilities.AXISYMMETRIC:
            raise scene_error("axisymmetric scenes are not supported yet")
        return value

    @model_validator(mode="after")
    def _material_method_defaults(self) -> "Scene":
        """The method keys the scene leaves out take the default its materials set
        (BaseMaterial.method_defaults: the ideal gas's cubic B-splines), where they agree and the
        method allows it; a key the scene gives is kept. The one place a default depends on the
        material: the scene holds the resolved method (`mpm validate` prints it)."""
        wanted: dict[str, set] = {}
        for material in self.materials.values():
            for key, value in material.method_defaults.items():
                wanted.setdefault(key, set()).add(value)
        given = self.method.model_dump(exclude_unset=True)
        resolved = {key: values.pop() for key, values in wanted.items()
                    if len(values) == 1 and key not in given}
        if resolved:
            try:
                self.method = Method.model_validate({**given, **resolved})
            except ValidationError:   # (a formulation the material's choice does not work with)
                pass
        return self

    @model_validator(mode="after")
    def _consistent(self) -> "Scene":
        problems = cross_checks(self)
        if problems:
            raise problems_at(problems)
        return self

    # Grid helpers for the solver. The number of cells per axis is
    # n = ceil((upper - lower) / h) (ignoring round-off), and the grid really ends
    # at lower + n h, which may lie a little above the given upper.

    def cell_sizes(self) -> tuple[float, ...]:
        size = self.grid.cell_size
        return tuple(size) if isinstance(size, list) else (size,) * self.dimension

    def grid_lower(self) -> tuple[float, ...]:
        if self.grid.lower is not None:
            return tuple(self.grid.lower)
        lower, _ = self._bodies_box()
        return tuple(lower - 2 * np.array(self.cell_sizes()))

    def grid_shape(self) -> tuple[int, ...]:
        """Number of cells per axis."""
        sizes = self.cell_sizes()
        if self.grid.upper is not None:
            upper = self.grid.upper
        else:
            upper = [float(u) + 2 * h for u, h in zip(self._bodies_box()[1], sizes)]
        # Python floats (the same IEEE operations as numpy's, without its per-call cost: this
        # runs for every body); an infinite extent gives inf, counted as MAX_COUNT cells
        cells = [max(1, count_up((u - lo) / h - 1e-9)) for u, lo, h in zip(upper, self.grid_lower(), sizes)]
        if shape_functions.REGISTRY[self.method.shape_function].even_cells:   # elements of two cells (bernstein)
            cells = [n + n % 2 for n in cells]
        return tuple(cells)

    def grid_fields(self) -> int:
        """Velocity fields the grid holds: one per body with contact "friction", else one."""
        return len(self.bodies) if self.contact.fields else 1

    def grid_upper(self) -> tuple[float, ...]:
        return tuple(lo + n * h for lo, n, h in zip(self.grid_lower(), self.grid_shape(), self.cell_sizes()))

    def _bodies_box(self) -> tuple[np.ndarray, np.ndarray]:
        boxes = [body.geometry.shape().bounding_box() for body in self.bodies]
        return np.min([b[0] for b in boxes], axis=0), np.max([b[1] for b in boxes], axis=0)


def _rebuild_material_union() -> None:
    """A material was registered or removed: the scene validates (and its JSON schema
    describes) the registered ones from now on."""
    global Material
    Material = _material_union()
    Scene.model_fields["materials"].annotation = dict[str, Material]
    Scene.model_rebuild(force=True)


material_registry.on_change(_rebuild_material_union)


# --------------------------------------------------------------------------- reading

def parse_scene(source: "str | Path | dict | Scene", files: "str | Path | None" = None) -> Scene:
    """A scene given as a path to a JSON file, JSON text, a dict or a Scene, validated against
    the schema (solver.scene_checks.load_scene checks its size and time step after this).

    `files`: the folder the scene's relative file names (mesh files) start from; a scene
    read from a file reads them beside it. Without it a scene given as a document may not
    name files at all (what the service relies on: it never opens a path named in a scene).

    Raises SceneError listing every problem found."""
    if isinstance(source, Scene):
        return source
    data = _read(source)
    if files is None and _is_path(source):
        files = Path(source).resolve().parent
    try:
        return Scene.model_validate(data, context={"files": files, "polygons": [0, 0, False]})
    except ValidationError as exc:
        raise SceneError(_format_errors(exc, data)) from None


def _is_path(source: Any) -> bool:
    return isinstance(source, Path) or (isinstance(source, str) and not source.lstrip().startswith(("{", "[")))


def _read(source: Any) -> dict:
    if isinstance(source, dict):
        return source
    if _is_path(source):
        try:
            text = Path(source).read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise SceneError([{"path": "", "message": f"cannot read the scene file {str(source)!r}: {exc}"}]) from None
    elif isinstance(source, str):
        text = source
    else:
        raise SceneError([{"path": "", "message": f"a scene is a path, JSON text or a dict, not {type(source).__name__}"}])
    try:
        data = json.loads(text)
    except json.JSONDecodeError as exc:
        raise SceneError([{"path": "", "message": f"invalid JSON at line {exc.lineno}, column {exc.colno}: {exc.msg}"}]) from None
    if not isinstance(data, dict):
        raise SceneError([{"path": "", "message": "a scene must be a JSON object"}])
    return data


def _format_errors(exc: ValidationError, data: Any) -> list[dict[str, str]]:
    errors = []
    for error in exc.errors():
        loc = _without_tags(error["loc"], data)
        if error["type"] == "scene_problems":
            errors += [{"path": _join(_path(loc), rel), "message": message} for rel, message in error["ctx"]["problems"]]
        elif error["type"] in ("union_tag_invalid", "union_tag_not_found"):
            key = error["ctx"]["discriminator"].strip("'")
            message = (f"unknown {key} {error['ctx']['tag']!r}; expected one of {error['ctx']['expected_tags']}"
                       if error["type"] == "union_tag_invalid" else "required")
            errors.append({"path": _join(_path(loc), key), "message": message})
        else:
            errors.append({"path": _path(loc), "message": _message(error)})
    return errors


def _without_tags(loc: tuple, data: Any) -> list:
    """Drop the discriminator tags pydantic puts in locations ('sphere' in
    bodies.0.sphere.radius), found by walking the input alongside the location."""
    kept = []
    node = data
    tag_skipped = False
    for item in loc:
        # A tag comes right after the union's position, even where a key has the
        # same name as the tag ({"type": "velocity", "velocity": [...]}).
        # "model" tags materials and their parts, not the contact ({"model": "friction", "friction": 0.3})
        tags = (node.get("type"), node.get("model") if kept[:1] != ["contact"] else None) \
            if isinstance(node, dict) else ()
        if not tag_skipped and isinstance(item, str) and item in tags:
            tag_skipped = True
            continue
        tag_skipped = False
        kept.append(item)
        if isinstance(node, dict):
            node = node.get(item)
        elif isinstance(node, (list, tuple)) and isinstance(item, int) and 0 <= item < len(node):
            node = node[item]
        else:
            node = None
    return kept


def _path(loc: list) -> str:
    path = ""
    for item in loc:
        path += f"[{item}]" if isinstance(item, int) else (f".{item}" if path else str(item))
    return path


def _join(base: str, relative: str) -> str:
    if not base or not relative or relative.startswith("["):
        return base + relative
    return f"{base}.{relative}"


_COMPARISON_MESSAGES = {
    "greater_than": ("gt", ">"),
    "greater_than_equal": ("ge", ">="),
    "less_than": ("lt", "<"),
    "less_than_equal": ("le", "<="),
}


def _message(error: dict) -> str:
    kind = error["type"]
    if kind in _COMPARISON_MESSAGES:
        key, symbol = _COMPARISON_MESSAGES[kind]
        return f"must be {symbol} {fmt(error['ctx'][key])}"
    if kind == "missing":
        return "required"
    if kind == "too_short":
        return f"must have at least {error['ctx']['min_length']} item(s)"
    if kind == "too_long":
        return f"must have at most {error['ctx']['max_length']} item(s)"
    if kind == "extra_forbidden":
        return "unknown key (not part of the scene format)"
    message = error["msg"]
    for prefix in ("Value error, ", "Assertion failed, "):
        message = message.removeprefix(prefix)
    return message.replace("Input should be", "must be")
