"""Run-time estimates from a measured cost model.

A run costs its start-up (the interpreter, loading the compiled kernels, seeding,
the result file and the preview), its frames and its steps; a step costs

    t_step = a_d + b_d N + sum over materials (c_k f_k + m_model) P_model / S(T)

with N grid nodes, P_model particles of each material, a_d and b_d the fixed and
per-node cost of a step in d dimensions, c_k the per-particle cost of the step's
kind k = (dimension, backend, formulation, shape function) with a linear elastic
material, FLIP and MUSL, f_k the product of the factors of the scene's transfer,
scheme and axisymmetry, m_model what the material's stress update adds over linear
elasticity, and S(T) the speed-up of T threads (Amdahl's law with the parallel share
measured at the calibration's thread count).

The figures come from `mpm calibrate` (solver/calibrate.py), stored in the user's
cache folder (`calibration_path()`); without that, the model shipped with the
package (`SHIPPED`, measured on the development machine) is used. `source` says which.
A kernel variant not yet in numba's cache compiles on its first run (seconds to a
minute): `compile_seconds` adds the measured compile time of the scene's kind unless a
run of the same variant (`variant`: the scene's structure, its numbers left out) has
marked it compiled in this version's kernel cache (solver/kernel_cache.py).
"""
from __future__ import annotations

import functools
import hashlib
import json
import os
from pathlib import Path

from pydantic import BaseModel, Field

from solver import fused_scope, kernel_cache
from solver.expressions import compile_expression
from solver import shape as shape_functions
from solver.scene import BODY_FORCE_VARIABLES
from solver.thread_count import pool_size, requested_threads

SHIPPED = Path(__file__).with_name("cost_model.json")
VERSION = 1


def calibration_path() -> Path:
    """Where `mpm calibrate` stores this machine's model: the user's cache folder."""
    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return cache / "mpm-solver" / "cost_model.json"


class ThreadScaling(BaseModel):
    threads: int = Field(description="the thread count the speed-up was measured at")
    speedup: float = Field(description="time with one thread / time with `threads`")

    def at(self, threads: int) -> float:
        """Speed-up at `threads` by Amdahl's law, its parallel share p from the measurement. A
        measured speed-up below 1 (threads that waited for each other on a busy machine) is
        taken as it is, for any thread count above 1."""
        if threads <= 1 or self.threads <= 1:
            return 1.0
        if self.speedup < 1.0:
            return self.speedup
        measured = min(self.speedup, float(self.threads))
        p = (1.0 - 1.0 / measured) / (1.0 - 1.0 / self.threads)
        return 1.0 / ((1.0 - p) + p / threads)


class CostModel(BaseModel):
    version: int = VERSION
    machine: str = Field("", description="where it was measured (host name, cores)")
    measured_at: str = ""
    startup_seconds: float = Field(description="a run of a tiny scene, from the command to its exit")
    startup_extra_seconds: dict[str, float] = Field(
        default_factory=dict, description="'<dim>/<backend>/<shape>': what a run of that kind adds to the start-up "
                                          "(kernels that compile in every process)")
    frame_particle_seconds: float = Field(description="per particle and output frame")
    step_seconds: dict[str, float] = Field(description="'<dim>/<backend>': fixed cost of a step")
    node_seconds: dict[str, float] = Field(description="'<dim>/<backend>': per grid node and step")
    particle_seconds: dict[str, float] = Field(
        description="'<dim>/<backend>/<formulation>/<shape>': per particle and step, linear elastic, flip, musl")
    material_seconds: dict[str, float] = Field(description="'<dim>/<model>': added per particle and step")
    expression_seconds: float = Field(0.0, description="per particle, step and instruction of the body_force "
                                                       "expressions (evaluated at every particle every step)")
    factors: dict[str, float] = Field(description="'<backend>/<transfer or scheme>', 'axisymmetric': "
                                                  "multiply the per-particle cost")
    thread_scaling: dict[str, ThreadScaling] = Field(description="'<dim>/<backend>'")
    compile_seconds: dict[str, float] = Field(
        default_factory=dict, description="'<dim>/<backend>': compiling a new variant's step on an empty cache; "
                                          "'<dim>/<model>': what a material model adds")
    source: str = Field("", exclude=True, description="the file it was read from")


@functools.cache
def _read(path: str, mtime: float) -> CostModel | None:
    try:
        model = CostModel.model_validate_json(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    return model if model.version == VERSION else None


def load_model() -> CostModel:
    """This machine's calibration when there is a valid one, else the shipped model."""
    for path in (calibration_path(), SHIPPED):
        try:
            model = _read(str(path), path.stat().st_mtime)
        except OSError:
            continue
        if model is not None:
            return model.model_copy(update={"source": str(path)})
    raise FileNotFoundError(f"no cost model: {SHIPPED} is missing from the package")


def planned_threads(scene, particles: int) -> int:
    """The threads per process a run of the scene will take (solver/threads.configure)."""
    return max(1, min(requested_threads(scene, particles), pool_size()))


def backend_name(scene) -> str:
    """'fused' or 'general': the step's backend (solver/step: the fused one where it applies)."""
    return "fused" if fused_scope.supports(scene) else "general"


def _lookup(table: dict[str, float], key: str, fallbacks: list[str]) -> tuple[float, str]:
    for candidate in [key, *fallbacks]:
        if candidate in table:
            return table[candidate], candidate
    raise KeyError(key)


def _kind_seconds(model: CostModel, dim: int, backend: str, formulation: str, name: str) -> float:
    """c_k: measured, else the same shape function in the other formulation times the ratio of
    the two formulations' linear figures, else the linear figure times the nodes a particle
    touches over linear's."""
    table = model.particle_seconds
    key = f"{dim}/{backend}/{formulation}/{name}"
    if key in table:
        return table[key]
    mine = table.get(f"{dim}/{backend}/{formulation}/linear")
    for other in ("ulmpm", "tlmpm"):
        theirs, shape_key = table.get(f"{dim}/{backend}/{other}/linear"), f"{dim}/{backend}/{other}/{name}"
        if shape_key in table and mine and theirs:
            return table[shape_key] * mine / theirs
    linear, _ = _lookup(table, f"{dim}/{backend}/{formulation}/linear", [f"{dim}/general/ulmpm/linear"])
    return linear * (shape_functions.REGISTRY[name].support / 2) ** dim


def particle_step_seconds(model: CostModel, scene, backend: str) -> float:
    """c_k f_k: one particle's step with a linear elastic material, before threads."""
    method = scene.method
    base = _kind_seconds(model, scene.dimension, backend, method.formulation, method.shape_function)
    factor = model.factors.get(f"{backend}/{method.transfer}", 1.0) * model.factors.get(
        f"{backend}/{method.scheme}", 1.0)
    if scene.axisymmetric:
        factor *= model.factors.get("axisymmetric", 1.0)
    return base * factor


def _expression_seconds(model: CostModel, scene) -> float:
    """Per particle and step: the body_force expressions, evaluated with numpy in the step."""
    operations = sum(compile_expression(c, BODY_FORCE_VARIABLES, scene.expressions).operations
                     for c in scene.body_force or () if isinstance(c, str))
    return model.expression_seconds * operations


def estimate_seconds(scene, particles_per_body: list[int], nodes: int, steps: int,
                     model: CostModel | None = None) -> float:
    """Wall time of a run from start to exit, with numba's cache warm (`compile_seconds` adds
    the compilation of a new variant)."""
    model = model or load_model()
    dim = scene.dimension
    backend = backend_name(scene)
    particles = sum(particles_per_body)
    per_particle = particle_step_seconds(model, scene, backend)
    material_time = 0.0
    for body, count in zip(scene.bodies, particles_per_body):
        name = scene.materials[body.material].model
        added = model.material_seconds.get(f"{dim}/{name}", model.material_seconds.get(f"2/{name}", 0.0))
        material_time += count * added
    threads = planned_threads(scene, particles) * scene.parallel.processes
    scaling = model.thread_scaling.get(f"{dim}/{backend}")
    speedup = scaling.at(threads) if scaling is not None else 1.0
    fixed, _ = _lookup(model.step_seconds, f"{dim}/{backend}", [f"{dim}/general", "2/general"])
    per_node, _ = _lookup(model.node_seconds, f"{dim}/{backend}", [f"{dim}/general", "2/general"])
    step = fixed + (per_node * nodes + (per_particle + _expression_seconds(model, scene)) * particles
                    + material_time) / speedup
    frames = model.frame_particle_seconds * particles * scene.output.frames
    startup = model.startup_seconds + model.startup_extra_seconds.get(
        f"{dim}/{backend}/{scene.method.shape_function}", 0.0)
    return startup + frames + steps * step



# Compile time of a variant when the model has no figure for its kind (a 2D elastic step, measured).
DEFAULT_COMPILE_SECONDS = 30.0
# A run on one thread compiles the kernels' serial twins (solver/jit.py): about this share
# of the model's figures, which are the parallel forms' (docs/internals.md, "One thread,
# serial twins": the twins' compile time over the parallel forms', cold, per example).
ONE_THREAD_COMPILE = 0.6
# Parts of a scene that change no kernel: names, labels, output and timing.
_NOT_COMPILED = {"name", "material", "units", "output", "time", "version"}


def _structure(value):
    """`value` with its numbers and names left out and its lists as sorted sets: what decides
    which kernels a run compiles (the kernels take the numbers as arguments)."""
    if isinstance(value, dict):
        return {key: _structure(item) for key, item in sorted(value.items()) if key not in _NOT_COMPILED}
    if isinstance(value, list):
        return sorted({json.dumps(_structure(item), sort_keys=True) for item in value})
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return value
    return "#"


def variant(scene, threads: int) -> str:
    """A digest of what decides the kernels a run of `scene` on `threads` threads a process
    compiles (one thread: the serial twins, solver/jit.py)."""
    data = scene.model_dump(mode="json")
    data["materials"] = list(data["materials"].values())   # their names are the user's
    data["parallel"] = {"processes": min(scene.parallel.processes, 2),   # one or several: MPI's kernels
                        "one_thread": threads == 1}
    data["backend"] = backend_name(scene)
    return hashlib.sha256(json.dumps(_structure(data), sort_keys=True).encode()).hexdigest()[:16]


def _compiled_marker(scene, threads: int) -> Path:
    return kernel_cache.version_folder() / "compiled" / f"{variant(scene, threads)}.json"


def is_compiled(scene, threads: int) -> bool:
    """Whether a run of this variant compiled its kernels into this version's cache."""
    return _compiled_marker(scene, threads).exists()


def mark_compiled(scene, threads: int, seconds: float, count: int) -> None:
    """Record that this variant's kernels are in the cache (after a run's first step)."""
    marker = _compiled_marker(scene, threads)
    try:
        marker.parent.mkdir(parents=True, exist_ok=True)
        temporary = marker.with_name(f".{marker.name}.{os.getpid()}")
        temporary.write_text(json.dumps({"compile_seconds": round(seconds, 3), "compiled": count}))
        os.replace(temporary, marker)
    except OSError:
        pass   # a read-only cache: later estimates count the compilation again, nothing worse


def compile_seconds(scene, threads: int, model: CostModel | None = None) -> float:
    """Wall time a run on `threads` threads a process will spend compiling: 0 for a variant
    compiled before, else the model's figure for the scene's kind plus what its materials'
    models add (a share of it on one thread)."""
    if is_compiled(scene, threads):
        return 0.0
    model = model or load_model()
    # `mpm calibrate` measures steps, not compilation: a calibration takes the shipped figures
    table, dim = model.compile_seconds or _read(str(SHIPPED), SHIPPED.stat().st_mtime).compile_seconds, scene.dimension
    seconds = table.get(f"{dim}/{backend_name(scene)}", DEFAULT_COMPILE_SECONDS)
    models = {material.model for material in scene.materials.values()}
    parallel_forms = seconds + sum(table.get(f"{dim}/{name}", 0.0) for name in models)
    return parallel_forms * (ONE_THREAD_COMPILE if threads == 1 else 1.0)
