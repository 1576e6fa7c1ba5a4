"""`mpm calibrate`: measure this machine's cost model (solver/cost.py) and store it.

Every figure is a time per step of a small block of particles stepped in this process
(numba's cache warm: two untimed steps first, which compile a variant that is not in
the cache), the median of REPEATS repeats of enough steps for about REPEAT_SECONDS each:

  a_d, b_d   the fixed and per-node cost of a step: the linear elastic block at two
             particle counts on one grid, and on a grid with four times the nodes
  c_k        per particle, each (dimension, backend, formulation, shape function)
  m_model    what each material adds per particle over linear elasticity
  body force the evaluation of body_force expressions, per particle and instruction
  factors    transfers and schemes against FLIP and MUSL, axisymmetry (2D)
  threads    the base blocks on all the cores this process may use, against one
  frames     a run() with 42 frames against one with 2, per particle and frame
  start-up   `python -m solver run` of a tiny scene, from the command to its exit

On a quiet 2-core machine it takes a few minutes (more the first time, while the
variants compile). Timings on a loaded machine come out slower, and so do estimates.
"""
from __future__ import annotations

import json
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

from solver import fused_scope
from solver import shape as shape_functions
from solver.cost import CostModel, calibration_path
from solver.thread_count import available_cores

REPEAT_SECONDS = 0.1
# the median of this many: the machine's typical speed, with the load it has while calibrating
# (the best of them measured a quiet moment, and estimates came out 2-4x short of whole runs)
REPEATS = 7
# a transfer's, scheme's or axisymmetry's factor outside this range is noise, not a measurement
FACTOR_RANGE = (0.25, 4.0)
BLOCK_PARTICLES = {1: 3000, 2: 6000, 3: 6000}   # the large block; the small one has an eighth
H = 0.1
PPC = 2

MATERIALS = {
    "linear_elastic": {"model": "linear_elastic", "density": 1000.0, "youngs_modulus": 1e6, "poisson_ratio": 0.3},
    "neo_hookean": {"model": "neo_hookean", "density": 1000.0, "youngs_modulus": 1e6, "poisson_ratio": 0.3},
    "j2_plasticity": {"model": "j2_plasticity", "density": 7800.0, "youngs_modulus": 2e11, "poisson_ratio": 0.3,
                      "yield_stress": 7e8, "hardening_modulus": 3e8},
    "johnson_cook": {"model": "johnson_cook", "density": 8940.0, "youngs_modulus": 115e9, "poisson_ratio": 0.31,
                     "A": 65e6, "B": 356e6, "n": 0.37, "C": 0.013, "reference_strain_rate": 1.0, "m": 1.09,
                     "room_temperature": 298.0, "melt_temperature": 1356.0, "specific_heat": 383.0,
                     "taylor_quinney": 0.9, "eos": {"model": "mie_gruneisen", "c0": 3933.0, "s": 1.5, "gamma0": 2.0}},
    "fluid": {"model": "fluid", "density": 1000.0, "bulk_modulus": 3.5e5, "gamma": 7.0, "viscosity": 0.001},
    "ideal_gas": {"model": "ideal_gas", "gamma": 1.4},
}
# a compression of the block at this strain rate (1/s) makes the plastic models yield within a few steps
SQUEEZE = {"j2_plasticity": 20.0, "johnson_cook": 20.0}


def block_scene(dim: int, particles: int, grid_factor: float = 1.0, material: str = "linear_elastic",
                threads: int = 1, **method) -> dict:
    """A block of about `particles` particles (PPC per cell and axis) in a grid 3 cells wider
    on each side, scaled to `grid_factor` times the nodes."""
    cells = max(2, round((particles / PPC**dim) ** (1 / dim)))
    lower, upper = [4 * H] * dim, [4 * H + cells * H] * dim
    span = (cells + 8) * grid_factor ** (1 / dim)
    body = {"name": "block", "material": "m", "particles_per_cell": PPC,
            "geometry": {"type": "box", "lower": lower, "upper": upper}}
    centre = 4 * H + cells * H / 2
    rate = SQUEEZE.get(material, 0.01)
    body["initial_velocity"] = [f"-{rate} * ({axis} - {centre})" for axis in "xyz"[:dim]]
    walls = []
    if material == "ideal_gas":   # a gas expands: slip walls keep it on the grid
        body.update(initial_density=1.0, initial_pressure=1e5)
        walls = [{"type": "wall", "face": f"{axis}{side}", "mode": "slip"} for axis in "xyz"[:dim] for side in "-+"]
    return {"dimension": dim, "method": {"formulation": "ulmpm", **method},
            "grid": {"lower": [0.0] * dim, "upper": [span * H] * dim, "cell_size": H},
            "materials": {"m": MATERIALS[material]}, "bodies": [body], "boundary_conditions": walls,
            "time": {"end": 1.0}, "output": {"energies": False}, "parallel": {"threads": threads}}


def step_seconds(document: dict, general: bool = False) -> tuple[float, int, int]:
    """(seconds per step, particles, nodes) of a scene stepped here."""
    from solver.runner import make_simulation
    from solver.scene_checks import load_scene
    from solver.stepper import ExplicitMPM

    scene = load_scene(document)
    sim = ExplicitMPM(scene, general=True) if general else make_simulation(scene)

    def advance(steps: int) -> float:
        start = time.perf_counter()
        for _ in range(steps):
            sim.advance(scene.time.dt or sim.stable_time_step(scene.time.cfl))
        return time.perf_counter() - start

    advance(2)
    steps = int(min(200, max(3, REPEAT_SECONDS / max(advance(1), 1e-6))))
    typical = statistics.median(advance(steps) for _ in range(REPEATS)) / steps
    return typical, sim.particles.count, sim.grid.n_nodes


def _fixed_and_nodes(dim: int, backend: str) -> tuple[float, float, float, dict]:
    """a_d, b_d and c of the base kind, from three blocks."""
    general = backend == "general"
    big = BLOCK_PARTICLES[dim]
    t1, p1, n1 = step_seconds(block_scene(dim, big // 8), general)
    t2, p2, n2 = step_seconds(block_scene(dim, big), general)
    t3, p3, n3 = step_seconds(block_scene(dim, big, grid_factor=4.0), general)
    per_particle = max((t2 - t1) / (p2 - p1), 0.0)
    per_node = max((t3 - t2) / (n3 - n2), 0.0)
    fixed = max(t1 - per_node * n1 - per_particle * p1, 0.0)
    return fixed, per_node, per_particle, {"particles": p2, "nodes": n2}


def _kinds(dim: int):
    """(backend, formulation, shape function) of the kinds measured in `dim` dimensions: every
    shape function in one formulation (ulmpm where it may), tlmpm with linear hats, the fused
    kernels' shapes (solver/cost.py scales a kind not measured from these)."""
    for name, declared in shape_functions.REGISTRY.items():
        yield "general", "ulmpm" if "ulmpm" in declared.formulations else sorted(declared.formulations)[0], name
    yield "general", "tlmpm", "linear"
    if dim > 1:
        for name in sorted(fused_scope.FUSED_SHAPES):
            yield "fused", "ulmpm", name


def _per_particle(model: dict, dim: int, backend: str, seconds: float, particles: int, nodes: int) -> float:
    key = f"{dim}/{backend}"
    rest = seconds - model["step_seconds"][key] - model["node_seconds"][key] * nodes
    return max(rest / particles, 0.0)


def measure_kinds(model: dict, dim: int, log) -> None:
    for backend in (("general", "fused") if dim > 1 else ("general",)):
        fixed, per_node, per_particle, _ = _fixed_and_nodes(dim, backend)
        key = f"{dim}/{backend}"
        model["step_seconds"][key], model["node_seconds"][key] = fixed, per_node
        model["particle_seconds"][f"{key}/ulmpm/linear"] = per_particle
        log(f"{key}: {1e6 * fixed:.1f} us a step, {1e9 * per_node:.1f} ns a node, {1e9 * per_particle:.0f} ns a particle")
    for backend, formulation, name in _kinds(dim):
        key = f"{dim}/{backend}/{formulation}/{name}"
        if key in model["particle_seconds"]:
            continue
        document = block_scene(dim, BLOCK_PARTICLES[dim], formulation=formulation, shape_function=name)
        try:
            seconds, particles, nodes = step_seconds(document, general=backend == "general")
        except Exception as error:   # a kind this dimension cannot step (a scene rule): not calibrated
            log(f"{key}: skipped ({type(error).__name__}: {str(error)[:80]})")
            continue
        model["particle_seconds"][key] = _per_particle(model, dim, backend, seconds, particles, nodes)
        log(f"{key}: {1e9 * model['particle_seconds'][key]:.0f} ns a particle")


def measure_materials(model: dict, log) -> None:
    for dim in (2, 3):
        base = model["particle_seconds"][f"{dim}/fused/ulmpm/linear"]
        for name in MATERIALS:
            if name == "linear_elastic":
                continue
            seconds, particles, nodes = step_seconds(block_scene(dim, BLOCK_PARTICLES[dim], material=name))
            added = _per_particle(model, dim, "fused", seconds, particles, nodes) - base
            model["material_seconds"][f"{dim}/{name}"] = max(added, 0.0)
            log(f"{dim}/{name}: + {1e9 * added:.0f} ns a particle")


FACTOR_CASES = {   # (backend, name): (method of the case, method of its reference)
    ("fused", "pic"): ({"transfer": "pic"}, {}),
    ("fused", "apic"): ({"transfer": "apic", "shape_function": "quadratic_bspline"},
                        {"shape_function": "quadratic_bspline"}),
    ("fused", "usl"): ({"scheme": "usl"}, {}),
    ("general", "pic"): ({"transfer": "pic"}, {}),
    ("general", "apic"): ({"transfer": "apic", "shape_function": "quadratic_bspline"},
                          {"shape_function": "quadratic_bspline"}),
    ("general", "usl"): ({"scheme": "usl"}, {}),
    ("general", "usf"): ({"scheme": "usf"}, {}),
}


def measure_factors(model: dict, log) -> None:
    dim, big = 2, BLOCK_PARTICLES[2]
    for (backend, name), (method, reference) in FACTOR_CASES.items():
        general = backend == "general"
        case = _per_particle(model, dim, backend, *step_seconds(block_scene(dim, big, **method), general))
        ref = _per_particle(model, dim, backend, *step_seconds(block_scene(dim, big, **reference), general))
        _set_factor(model, f"{backend}/{name}", case, ref, log)
    document = block_scene(dim, big)
    document["axisymmetric"] = True
    axisymmetric = _per_particle(model, dim, "general", *step_seconds(document))
    _set_factor(model, "axisymmetric", axisymmetric, model["particle_seconds"]["2/general/ulmpm/linear"], log)
    if model["factors"]["axisymmetric"] < 1.0:   # the hoop terms only add work: below 1 is noise
        log(f"axisymmetric: x {model['factors']['axisymmetric']:.2f} below 1 (the hoop terms add work): 1 is stored")
        model["factors"]["axisymmetric"] = 1.0


def _set_factor(model: dict, key: str, case: float, reference: float, log) -> None:
    factor = case / reference if reference > 0 else 1.0
    if not FACTOR_RANGE[0] <= factor <= FACTOR_RANGE[1]:
        log(f"{key}: x {factor:.2f} is outside {FACTOR_RANGE} (a disturbed measurement): 1 is stored")
        factor = 1.0
    model["factors"][key] = factor
    log(f"{key}: x {factor:.2f}")


# a body force of about 100 instructions, mostly arithmetic with a few functions, as manufactured
# solutions are (examples/vortex_2d.json has 840 instructions, mms_square_2d.json 194)
# (small: the block must stay on its grid)
BODY_FORCE = " + ".join(f"1e-6 * (({k + 1} * (x * x + y * y) ** 2 / (1 + x) - 3 * y * t) * sqrt(1 + x * x) - sin(y))"
                        for k in range(4))


def measure_expressions(model: dict, log) -> None:
    """The body force's evaluation per particle, step and instruction (2D fused block)."""
    from solver.expressions import compile_expression
    from solver.scene import BODY_FORCE_VARIABLES

    plain = block_scene(2, BLOCK_PARTICLES[2])
    loaded = block_scene(2, BLOCK_PARTICLES[2])
    loaded["body_force"] = [BODY_FORCE, "0"]
    base, particles, _ = step_seconds(plain)
    with_force, _, _ = step_seconds(loaded)
    operations = compile_expression(BODY_FORCE, BODY_FORCE_VARIABLES).operations
    model["expression_seconds"] = max(with_force - base, 0.0) / (particles * operations)
    log(f"body force: {1e9 * model['expression_seconds']:.2f} ns a particle and instruction ({operations} instructions)")


def measure_threads(model: dict, log) -> None:
    """One thread against all cores, in interleaved pairs (a load that comes and goes hits
    both): the median of three ratios."""
    cores = available_cores()
    if cores < 2:
        log("threads: one core, no speed-up measured")
        return
    for dim in (1, 2, 3):
        for backend in (("general", "fused") if dim > 1 else ("general",)):
            general = backend == "general"
            ratios = [step_seconds(block_scene(dim, BLOCK_PARTICLES[dim]), general)[0]
                      / step_seconds(block_scene(dim, BLOCK_PARTICLES[dim], threads=cores), general)[0]
                      for _ in range(3)]
            model["thread_scaling"][f"{dim}/{backend}"] = {"threads": cores, "speedup": statistics.median(ratios)}
            log(f"{dim}/{backend}: {cores} threads {statistics.median(ratios):.2f} x one "
                f"(pairs: {', '.join(f'{r:.2f}' for r in ratios)})")


def measure_frames(model: dict, log) -> None:
    """run() of the 2D block for 40 steps with 42 frames and with 2."""
    from solver.runner import run

    walls = {}
    for frames in (2, 42):
        document = block_scene(2, BLOCK_PARTICLES[2])
        document["time"] = {"end": 40 * 1e-4, "dt": 1e-4}
        document["output"] = {"frames": frames, "energies": False}
        with tempfile.TemporaryDirectory(prefix="mpm-calibrate-") as tmp:
            walls[frames] = statistics.median(run(document, tmp).wall_seconds for _ in range(3))
    particles = step_seconds(block_scene(2, BLOCK_PARTICLES[2]))[1]
    model["frame_particle_seconds"] = max(walls[42] - walls[2], 0.0) / (40 * particles)
    log(f"frames: {1e9 * model['frame_particle_seconds']:.0f} ns a particle and frame")


def _run_seconds(document: dict, repeats: int) -> float:
    """Median wall time of `python -m solver run` of a scene, from the command to its exit."""
    walls = []
    with tempfile.TemporaryDirectory(prefix="mpm-calibrate-") as tmp:
        path = Path(tmp) / "tiny.json"
        path.write_text(json.dumps(document))
        for _ in range(repeats):
            start = time.perf_counter()
            subprocess.run([sys.executable, "-m", "solver", "run", str(path), "-o", str(Path(tmp) / "out"),
                            "--progress", "none"], check=True, capture_output=True)
            walls.append(time.perf_counter() - start)
    return statistics.median(walls)


def _tiny(dim: int, **method) -> dict:
    document = block_scene(dim, 4**dim, **method)
    document["time"] = {"end": 3e-4, "dt": 1e-4}
    document["output"] = {"frames": 2}
    return document


def measure_startup(model: dict, log) -> None:
    """`python -m solver run` of a few particles for a few steps, as mpm run does: the 2D fused
    block, then what each other kind adds (kernels that numba compiles in every process: the
    weights of shape functions passed as first-class functions are not cached)."""
    _run_seconds(_tiny(2), 1)   # compiles what the cache lacks
    model["startup_seconds"] = _run_seconds(_tiny(2), 3)
    log(f"start-up: {model['startup_seconds']:.2f} s")
    for dim in (1, 2, 3):
        for backend, formulation, name in _kinds(dim):
            document = _tiny(dim, formulation=formulation, shape_function=name)
            general = backend == "general" and dim > 1 and name in fused_scope.FUSED_SHAPES
            if general:   # the general backend for a shape the fused one has: a rigid body forces it
                continue
            try:
                _run_seconds(document, 1)
                extra = max(_run_seconds(document, 1) - model["startup_seconds"], 0.0)
            except subprocess.CalledProcessError as error:   # a disturbed run: this kind adds nothing known
                log(f"start-up {dim}/{backend}/{name}: failed ({error.stderr.decode()[-200:]!r}); not stored")
                continue
            model["startup_extra_seconds"][f"{dim}/{backend}/{name}"] = extra
            log(f"start-up {dim}/{backend}/{name}: + {extra:.2f} s")


def calibrate(log=print) -> CostModel:
    """Measure every figure of the cost model on this machine."""
    model = {"machine": f"{platform.node()} ({available_cores()} cores, {platform.processor() or platform.machine()})",
             "measured_at": datetime.now(timezone.utc).isoformat(timespec="seconds"),
             "step_seconds": {}, "node_seconds": {}, "particle_seconds": {}, "material_seconds": {},
             "factors": {}, "thread_scaling": {}, "startup_extra_seconds": {}}
    for dim in (1, 2, 3):
        measure_kinds(model, dim, log)
    measure_materials(model, log)
    measure_factors(model, log)
    measure_expressions(model, log)
    measure_threads(model, log)
    measure_frames(model, log)
    measure_startup(model, log)
    return CostModel.model_validate(model)


def save(model: CostModel, path: Path | None = None) -> Path:
    path = path or calibration_path()
    path.parent.mkdir(parents=True, exist_ok=True)
    partial = path.with_suffix(".tmp")
    partial.write_text(model.model_dump_json(indent=1) + "\n", encoding="utf-8")
    partial.replace(path)
    return path

