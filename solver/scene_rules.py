"""The rules that tie the parts of a structurally valid scene together: vector lengths against
`dimension`, names that refer to materials and bodies, bodies inside the grid, features that
do not go together. The scene's last validator (solver/scene.py, `Scene`) calls `cross_checks`
and reports every problem at its path.

This module reads a scene's models through their fields and their `type` names and imports
none of them, so the models sit above it. Like the scene, it loads without numba.
"""
from __future__ import annotations

from typing import Any

import numpy as np

from solver import capabilities
from solver import materials as material_registry
from solver import shape as shape_functions
from solver.boundary import face_material
from solver.expressions import compile_expression
from solver.parallel.slabs import scene_problems as slab_problems
from solver.pore_fluid_schema import pore_fluid_problems
from solver.schema import (
    AXIS_OF_VARIABLE,
    BODY_FORCE_VARIABLES,
    DEFAULT_FRAMES,
    MAX_COUNT,
    SPACE_VARIABLES,
    TIME_VARIABLES,
    fmt,
)
from solver.thermal_schema import thermal_problems

# The models of solver/scene.py, which sit above this module: named in the signatures for the
# reader, read through their fields.
Scene = Body = Tool = Any

# The keys of Body that give a body its initial state, for the materials that declare them
# (BaseMaterial.body_state_keys: ideal_gas).
BODY_STATE_KEYS = ("initial_density", "initial_pressure")


def cross_checks(scene: Scene) -> list[tuple[str, str]]:
    """The rules that tie parts of a structurally valid scene together."""
    dim = scene.dimension
    problems: list[tuple[str, str]] = []

    def length_ok(path: str, values: list | None) -> bool:
        if values is not None and len(values) != dim:
            problems.append((path, f"must have {dim} components (dimension is {dim}), got {len(values)}"))
            return False
        return True

    def expressions_ok(path: str, values: list | None, variables: tuple[str, ...]) -> None:
        for i, value in enumerate(values or []):
            if isinstance(value, str):
                used = compile_expression(value, variables, scene.expressions).variables_used
                for name in sorted(n for n in used if AXIS_OF_VARIABLE.get(n, -1) >= dim):
                    problems.append((f"{path}[{i}]", f"variable {name!r} does not exist in a {dim}D scene"))

    grid_ok = all([
        length_ok("grid.lower", scene.grid.lower),
        length_ok("grid.upper", scene.grid.upper),
        length_ok("grid.cell_size", scene.grid.cell_size if isinstance(scene.grid.cell_size, list) else None),
    ])
    if grid_ok and scene.grid.lower is not None and scene.grid.upper is not None:
        grid_ok = _grid_extent_ok(scene, problems)
    grid_ok = _grid_corners_given(scene, problems) and grid_ok

    length_ok("gravity", scene.gravity)
    if length_ok("body_force", scene.body_force):
        expressions_ok("body_force", scene.body_force, BODY_FORCE_VARIABLES)

    names: dict[str, int] = {}
    for i, body in enumerate(scene.bodies):
        path = f"bodies[{i}]"
        if body.name in names:
            problems.append((f"{path}.name", f"{body.name!r} is already the name of bodies[{names[body.name]}]"))
        names.setdefault(body.name, i)
        material = scene.materials.get(body.material)
        if material is None:
            defined = ", ".join(repr(name) for name in scene.materials)
            problems.append((f"{path}.material", f"unknown material {body.material!r}; defined: {defined}"))
        geometry_ok = _geometry_problems(f"{path}.geometry", body.geometry, dim, problems)
        if length_ok(f"{path}.initial_velocity", body.initial_velocity):
            expressions_ok(f"{path}.initial_velocity", body.initial_velocity, SPACE_VARIABLES)
        if material is not None:
            problems += _body_material_problems(path, body, material, length_ok)
            problems += _initial_stress_problems(path, body, material, scene)
        if scene.method.formulation == "ulmpm" and grid_ok and geometry_ok:
            problems += _outside_grid(f"{path}.geometry", body, scene)

    if grid_ok and (scene.grid.lower is None or scene.grid.upper is None) and not problems:
        grid_ok = _grid_extent_ok(scene, problems)   # the bodies' box (tlmpm), once the geometries are sound
    if grid_ok and scene.grid.lower is not None and scene.grid.upper is not None:
        problems += _shape_function_problems(scene)

    problems += _load_problems(scene, names, length_ok, expressions_ok)
    if scene.damping is not None and scene.parallel.processes > 1:   # the ghost nodes' share is not summed yet
        problems.append(("damping", f"is not supported yet with several processes "
                                    f"(parallel.processes = {scene.parallel.processes})"))

    for name, material in scene.materials.items():
        problems += material.scene_problems(f"materials.{name}", scene)
    problems += _frame_problems(scene)
    problems += _condition_problems(scene, length_ok)
    problems += thermal_problems(scene, length_ok)
    problems += pore_fluid_problems(scene, length_ok)
    problems += _contact_problems(scene, names)
    problems += _tool_problems(scene, length_ok, expressions_ok)
    if grid_ok:
        problems += slab_problems(scene)
    return problems


def _grid_corners_given(scene: Scene, problems: list[tuple[str, str]]) -> bool:
    """False where the formulation needs a grid corner the scene leaves out."""
    given = True
    if scene.axisymmetric and scene.grid.lower is not None and scene.grid.lower[0] < 0:
        problems.append(("grid.lower[0]", "must be >= 0 in an axisymmetric scene (x is the radius r)"))
    if scene.method.formulation == "ulmpm":
        for name in ("lower", "upper"):
            if getattr(scene.grid, name) is None:
                problems.append((f"grid.{name}", "required for formulation 'ulmpm'"))
                given = False
    if scene.axisymmetric and scene.method.formulation == "tlmpm" and scene.grid.lower is None:
        # (tlmpm's default grid is the bodies' box padded by two cells: it would reach r < 0)
        problems.append(("grid.lower", "required with formulation 'tlmpm' in an axisymmetric scene (with "
                         "lower[0] = 0 the axis r = 0 is a grid line whose nodes get v_r = 0)"))
    return given


def _grid_extent_ok(scene: Scene, problems: list[tuple[str, str]]) -> bool:
    """False (and the problem) when an axis has no finite count of cells: (upper - lower) /
    cell_size overflows (a grid from -1e308 to 1e308). A finite count, however large, is
    left to the limits, which name it with the setting."""
    counts = scene.grid_shape()
    axes = [a for a, n in enumerate(counts) if n >= MAX_COUNT]
    for a in axes:
        problems.append(("grid", f"axis {a}: (upper - lower) / cell_size is not a finite number of cells "
                                 f"(over {MAX_COUNT:.3g}); give a grid of sensible extent and cell size"))
    return not axes


def _frame_problems(scene: Scene) -> list[tuple[str, str]]:
    """At most a frame a step (first and last included): frames <= steps + 1, the steps being
    end / dt for a fixed dt, else time.max_steps (the run stops there whatever dt does).
    More frames than that would each make the runner shorten a step to land on it. Up to
    the default count (51) is always allowed: that bounds nothing worth refusing, and a
    scene whose dt is raised (a sweep over /time/dt, a coarse trial) keeps its frames."""
    steps = scene.time.fixed_steps()
    bound, source = (steps, "end / dt") if steps is not None else (scene.time.max_steps, "time.max_steps")
    if scene.output.frames <= max(bound + 1, DEFAULT_FRAMES):
        return []
    shown = scene.output.frames if scene.output.frames < MAX_COUNT else f"{scene.output.frames:.3g}"
    return [("output.frames", f"{shown} frames, more than the {bound} time steps ({source}) + 1: "
                              "a run writes at most one frame a step, the first and the last included")]



def _condition_problems(scene: Scene, length_ok) -> list[tuple[str, str]]:
    """Boundary conditions: vector lengths, faces that exist, one wall a face."""
    problems: list[tuple[str, str]] = []
    walls: dict[str, int] = {}
    for i, condition in enumerate(scene.boundary_conditions):
        path = f"boundary_conditions[{i}]"
        if condition.type == "velocity":
            if condition.where.type == "box":
                length_ok(f"{path}.where.lower", condition.where.lower)
                length_ok(f"{path}.where.upper", condition.where.upper)
            else:
                _geometry_problems(f"{path}.where", condition.where, scene.dimension, problems)
            length_ok(f"{path}.velocity", condition.velocity)
        elif condition.type in ("wall", "absorbing"):   # (thermal faces: thermal_problems)
            axis = "xyz".index(condition.face[0])
            if axis >= scene.dimension:
                problems.append((f"{path}.face", f"{condition.face!r} is not a face of a {scene.dimension}D grid"))
            elif condition.face in walls:
                other = walls[condition.face]
                problems.append((f"{path}.face", f"face {condition.face!r} already has a "
                                                 f"{'wall' if other[1] == 'wall' else 'boundary condition'} "
                                                 f"(boundary_conditions[{other[0]}])"))
            elif condition.type == "absorbing":
                problems += _absorbing_problems(path, condition, scene)
            walls.setdefault(condition.face, (i, condition.type))
    return problems


def _absorbing_problems(path: str, condition: Any, scene: Scene) -> list[tuple[str, str]]:
    """Dashpots need one elastic material at the face, one process, a planar scene."""
    if scene.axisymmetric:
        return [(f"{path}.type", "absorbing boundaries are not supported yet in axisymmetric scenes")]
    if scene.parallel.processes > 1:
        return [(f"{path}.type", f"absorbing boundaries are not supported yet with several processes "
                                 f"(parallel.processes = {scene.parallel.processes})")]
    material = face_material(scene, condition.face)
    if material is None or not hasattr(material, "lame_parameters"):
        return [(f"{path}.face", "the bodies that reach this face (within a cell) must be of one elastic "
                                 "material: its impedances rho c_p and rho c_s make the dashpots")]
    return []


def _contact_problems(scene: Scene, names: dict[str, int]) -> list[tuple[str, str]]:
    """Contact pairs name two different bodies once; the per-body fields need ULMPM and fit in memory."""
    contact = scene.contact
    problems: list[tuple[str, str]] = []
    seen: dict[frozenset, int] = {}
    for i, pair in enumerate(contact.pairs):
        path = f"contact.pairs[{i}].bodies"
        unknown = [name for name in pair.bodies if name not in names]
        for name in unknown:
            defined = ", ".join(repr(n) for n in names)
            problems.append((path, f"unknown body {name!r}; defined: {defined}"))
        key = frozenset(pair.bodies)
        if len(key) < 2:
            problems.append((path, f"a pair of two different bodies, got {pair.bodies[0]!r} twice"))
        elif key in seen:
            problems.append((path, f"the pair {sorted(key)} is already listed (contact.pairs[{seen[key]}])"))
        seen.setdefault(key, i)
    if not contact.fields:
        if contact.pairs or contact.friction:
            problems.append(("contact.model", "'single_field' has no friction or pairs: use model 'friction'"))
        return problems
    if scene.method.formulation != "ulmpm":
        problems.append(("contact.model", f"{contact.model!r} needs formulation 'ulmpm' (the per-body fields are "
                                          f"grid fields of the updated-Lagrangian step; TLMPM takes `tools`)"))
    problems += _field_conflicts(scene)
    nodes = int(np.prod([n + 1 for n in scene.grid_shape()])) if scene.grid.lower is not None else 0
    needed = scene.grid_fields() * nodes * 8 * (2 + 4 * scene.dimension)   # grid arrays, normals, presence
    if needed > capabilities.MAX_CONTACT_FIELD_BYTES:
        problems.append(("contact.model", f"{scene.grid_fields()} velocity fields (one per body) of {nodes} nodes need "
                                          f"{needed / 2**30:.3g} GiB, more than the "
                                          f"{capabilities.MAX_CONTACT_FIELD_BYTES / 2**30:.3g} GiB allowed: "
                                          f"fewer bodies or a coarser grid"))
    return problems


def _tool_problems(scene: Scene, length_ok, expressions_ok) -> list[tuple[str, str]]:
    """Tools: names that give distinct reaction series, a geometry and velocity of the scene's
    dimension, and materials with a shear modulus for the stiffness to be a multiple of."""
    problems: list[tuple[str, str]] = []
    series = {body.name.replace("/", "_"): f"bodies[{b}]" for b, body in enumerate(scene.bodies)
              if _rigid(scene, body)}   # their reaction_<body>_<axis>
    for i, tool in enumerate(scene.tools):
        path = f"tools[{i}]"
        key = tool.name.replace("/", "_")
        if key in series:
            problems.append((f"{path}.name", f"{tool.name!r} is already the name of {series[key]} (their "
                                             f"reaction series reaction_{key}_<axis> would be the same)"))
        series.setdefault(key, path)
        _geometry_problems(f"{path}.geometry", tool.geometry, scene.dimension, problems)
        if length_ok(f"{path}.velocity", tool.velocity):
            expressions_ok(f"{path}.velocity", tool.velocity, TIME_VARIABLES)
        if scene.axisymmetric:
            problems.extend(_revolution_problems(path, tool))
    for b, body in enumerate(scene.bodies if scene.tools else ()):
        material = scene.materials.get(body.material)
        if material is not None and not material.rigid and not hasattr(material, "shear_modulus"):
            problems.append(("tools", f"a tool's stiffness is a multiple of the shear modulus of the material it "
                                      f"touches, and bodies[{b}] ({body.name!r}) is of material {body.material!r} "
                                      f"(model {material.model!r}), which has none"))
    return problems


def _revolution_problems(path: str, tool: Tool) -> list[tuple[str, str]]:
    """In an axisymmetric scene a tool is a body of revolution around the axis r = 0: its
    cross-section lies at r >= 0 (a face or an edge on the axis is the axis, no surface) and
    it moves along the axis only."""
    problems = []
    geometry = tool.geometry
    if geometry.type == "box" and geometry.lower[0] < 0:
        problems.append((f"{path}.geometry.lower[0]", "must be >= 0 in an axisymmetric scene (a box from r = 0 "
                                                      "is a cylinder)"))
    if geometry.type == "polygon" and min(x for x, _ in geometry.vertices) < 0:
        problems.append((f"{path}.geometry.vertices", "must have r = x >= 0 in an axisymmetric scene (the "
                                                      "cross-section of the tool of revolution)"))
    if geometry.type == "sphere" and geometry.center[0] != 0 and geometry.center[0] < geometry.radius:
        problems.append((f"{path}.geometry.center[0]", "must be 0 (a sphere) or at least the radius (a torus) in "
                                                       "an axisymmetric scene"))
    if tool.velocity is not None and tool.velocity[0] != 0:
        problems.append((f"{path}.velocity[0]", "must be 0 in an axisymmetric scene: a tool of revolution moves "
                                                "along the axis only"))
    return problems


def _field_conflicts(scene: Scene) -> list[tuple[str, str]]:
    """Features whose grid arrays hold one field: they would read or write only the first
    body's field (or past the end of their arrays) under contact "friction"; the tracked
    corners of cpdi_q4 and cpdi_tet4 move with one field's velocity. (Conduction holds every
    field: solver/thermal.py.)"""
    problems = []
    for i, condition in enumerate(scene.boundary_conditions):
        if condition.type == "absorbing":
            problems.append((f"boundary_conditions[{i}].type", "absorbing faces are not supported yet with "
                                                               f"contact {scene.contact.model!r}"))
    if shape_functions.REGISTRY[scene.method.shape_function].hook:   # cpdi_q4, cpdi_tet4: tracked corners
        problems.append(("method.shape_function", f"{scene.method.shape_function!r} is not supported yet with "
                                                  f"contact {scene.contact.model!r} (its corners move on one field)"))
    return problems


def _load_problems(scene: Scene, names: dict[str, int], length_ok, expressions_ok) -> list[tuple[str, str]]:
    """Each load names a deformable body, and its box and vector have the scene's dimension."""
    problems = []
    for i, load in enumerate(scene.loads):
        path = f"loads[{i}]"
        body = names.get(load.body)
        if body is None:
            defined = ", ".join(repr(name) for name in names)
            problems.append((f"{path}.body", f"unknown body {load.body!r}; defined: {defined}"))
        elif _rigid(scene, scene.bodies[body]):
            problems.append((f"{path}.body", f"{load.body!r} is a rigid body: it moves as prescribed, a load "
                                             "does not act on it"))
        elif load.type == "traction" and scene.bodies[body].geometry.type == "points":
            problems.append((f"{path}.type", f"{load.body!r} is given as points: a traction needs the surface "
                                             "of a body seeded on the lattice; use a force"))
        length_ok(f"{path}.where.lower", load.where.lower)
        length_ok(f"{path}.where.upper", load.where.upper)
        if length_ok(f"{path}.{load.type}", load.vector):
            expressions_ok(f"{path}.{load.type}", load.vector, TIME_VARIABLES)
    return problems


def _geometry_problems(path: str, spec: Any, dim: int, problems: list[tuple[str, str]]) -> bool:
    """Check vector lengths of a geometry tree against ``dim``; True if all fit."""
    if spec.type in ("union", "difference", "intersection"):
        results = [_geometry_problems(f"{path}.parts[{i}]", part, dim, problems) for i, part in enumerate(spec.parts)]
        for i, part in enumerate(spec.parts):
            if part.type == "points":
                problems.append((f"{path}.parts[{i}].type", "points are a body's particles, not a region: "
                                                            "they cannot be combined with other geometries"))
                results.append(False)
        return all(results)
    if spec.type == "points" and spec.shape().positions.shape[1] != dim:
        problems.append((f"{path}.{'positions' if spec.file is None else 'file'}",
                         f"the points have {spec.shape().positions.shape[1]} coordinates; the scene is {dim}D"))
        return False
    if spec.type == "cylinder" and dim != 3:
        problems.append((f"{path}.type", f"a cylinder is a 3D geometry; in {dim}D use a sphere or a box"))
        return False
    if spec.type == "polygon" and dim != 2:
        problems.append((f"{path}.type", f"a polygon is a 2D geometry; this scene is {dim}D"))
        return False
    if spec.type == "mesh" and dim != 3:
        problems.append((f"{path}.type", f"a mesh is a 3D geometry; this scene is {dim}D (use a polygon in 2D)"))
        return False
    ok = True
    for name in ("lower", "upper", "center"):
        values = getattr(spec, name, None)
        if values is not None and len(values) != dim:
            problems.append((f"{path}.{name}", f"must have {dim} components (dimension is {dim}), got {len(values)}"))
            ok = False
    return ok


def _rigid(scene: Scene, body: Body) -> bool:
    """Whether `body` is of a rigid material (not when its material is unknown: reported apart)."""
    material = scene.materials.get(body.material)
    return material is not None and material.rigid


def _body_material_problems(path: str, body: Body, material: Any, length_ok) -> list[tuple[str, str]]:
    problems = material.body_problems(path, body) + _body_state_problems(path, body, material)
    problems += material.temperature_problems(path, body)
    if material.rigid and body.initial_velocity is not None:
        problems.append((f"{path}.initial_velocity", "a 'rigid' body moves with its prescribed velocity; "
                                                     "use velocity instead"))
    if body.velocity is not None:
        if not material.rigid:
            problems.append((f"{path}.velocity", "a prescribed velocity needs a 'rigid' material; "
                                                 "use initial_velocity for deformable bodies"))
        else:
            length_ok(f"{path}.velocity", body.velocity)
    return problems


def _body_state_problems(path: str, body: Body, material: Any) -> list[tuple[str, str]]:
    """The body keys of an initial state (BODY_STATE_KEYS): given on a body exactly when its
    material takes its state from them (BaseMaterial.body_state_keys)."""
    problems = []
    for name in BODY_STATE_KEYS:
        if name in material.body_state_keys:
            if getattr(body, name) is None:
                problems.append((f"{path}.{name}", f"required for an {material.model!r} material"))
        elif getattr(body, name) is not None:
            users = " or ".join(repr(model) for model, declared in material_registry.REGISTRY.items()
                                if name in declared.schema.body_state_keys)
            problems.append((f"{path}.{name}", f"only used with an {users} material"))
    return problems


def _initial_stress_problems(path: str, body: Body, material: Any, scene: Scene) -> list[tuple[str, str]]:
    """A geostatic stress needs gravity along one axis, a solid with a density, and k0
    unless the material has a friction angle to take it from."""
    if body.initial_stress is None:
        return []
    path = f"{path}.initial_stress"
    gravity = [g for g in scene.gravity or [] if g != 0]
    problems = []
    if len(gravity) != 1:
        problems.append((path, "a geostatic stress needs a gravity along one axis of the grid "
                               f"(gravity is {scene.gravity})"))
    if material.rigid or material.body_state_keys:   # no stress of its own, or one its bodies give
        problems.append((path, f"not for a {material.model!r} material"))
    elif body.initial_stress.k0 is None and not hasattr(material, "default_k0"):
        problems.append((f"{path}.k0", f"required for a {material.model!r} material (the default 1 - sin(phi) "
                                       "needs a friction_angle)"))
    return problems


def _shape_function_problems(scene: Scene) -> list[tuple[str, str]]:
    """Grids too small for a function's stencil; bodies too close to the grid ends
    for functions without a boundary-modified variant (quadratic B-splines: a
    particle within h/2 of a grid end would need a node beyond it)."""
    name = scene.method.shape_function
    declared = shape_functions.REGISTRY[name]
    if scene.axisymmetric and not declared.axisymmetric:
        return [("method.shape_function", declared.axisymmetric_refusal)]
    if scene.dimension not in declared.dimensions:
        return [("method.shape_function", declared.dimension_refusal)]
    if min(scene.grid_shape()) < declared.least_cells:
        return [("grid.cell_size", f"{name!r} needs at least {declared.least_cells} cells per axis, "
                                   f"the grid has {list(scene.grid_shape())}")]
    if not declared.end_margin:
        return []
    problems = []
    margin = declared.end_margin * np.array(scene.cell_sizes())
    grid_lower, grid_upper = np.array(scene.grid_lower()), np.array(scene.grid_upper())
    for i, body in enumerate(scene.bodies):
        lower, upper = body.geometry.shape().bounding_box()
        if np.any(lower < grid_lower + margin - 1e-9 * margin) or np.any(upper > grid_upper - margin + 1e-9 * margin):
            problems.append((f"bodies[{i}].geometry", f"with {name!r} a body must keep {_cells(declared.end_margin)} "
                                                      "from the grid ends (its particles would need nodes "
                                                      "beyond the grid); enlarge the grid"))
    return problems


def _cells(count: float) -> str:
    return "half a cell" if count == 0.5 else f"{fmt(count)} cells"


def _outside_grid(path: str, body: Body, scene: Scene) -> list[tuple[str, str]]:
    lower, upper = body.geometry.shape().bounding_box()
    if scene.axisymmetric:   # the part at r < 0 is the mirror image of the cross-section: not seeded
        lower = np.array(lower, dtype=float)
        lower[0] = max(lower[0], 0.0)
    grid_lower, grid_upper = np.array(scene.grid_lower()), np.array(scene.grid_upper())
    tolerance = 1e-9 * max(scene.cell_sizes())
    if np.all(lower >= grid_lower - tolerance) and np.all(upper <= grid_upper + tolerance):
        return []
    box = " x ".join(f"[{fmt(lo)}, {fmt(up)}]" for lo, up in zip(lower, upper))
    grid = " x ".join(f"[{fmt(lo)}, {fmt(up)}]" for lo, up in zip(grid_lower, grid_upper))
    return [(path, f"the body (bounding box {box}) extends outside the grid {grid}")]
