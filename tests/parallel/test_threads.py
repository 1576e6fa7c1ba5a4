"""threads = 1 and 2 give the same particles after 200 steps (issue 9).

The scenes of test_equivalence.py (bodies colliding across slab boundaries, gravity,
a slip floor), plus 2D variants with quadratic B-splines, APIC and J2 plasticity, and MLS,
Drucker-Prager (2D) and Mohr-Coulomb (3D) variants and an axisymmetric Drucker-Prager billet:
these run the fused kernels. The general (stored-stencil) kernels run the others:
GIMP, cubic B-splines with APIC and with MLS, TLMPM with a rigid pusher, an axisymmetric J2
billet under a rigid platen.
Gathers and material updates give the same bits for any thread count; P2G adds
each thread's particles into its own copy of the grid and sums the copies, so the
sums differ in order only: round-off, held to the same 1e-12 relative as the
process counts. One run combines both: 2 processes of 2 threads each.
"""
from __future__ import annotations

import json
import subprocess
import sys

import numba
import numpy as np
import pytest

from ranks import AXISYMMETRIC, PORE_2D, SCENE_2D, SCENE_3D, TLMPM_2D, last_frame, relative_difference, run_cli, scene
from solver import fused
from solver.results import read_scene
from solver.scene_checks import load_scene
from solver.stepper import ExplicitMPM

TOLERANCE = 1e-12
STEPS = 200
PLASTIC = {"model": "j2_plasticity", "density": 1000, "youngs_modulus": 1000, "poisson_ratio": 0.3,
           "yield_stress": 5.0, "hardening_modulus": 50.0}
SOIL = {"density": 1000, "youngs_modulus": 1000, "poisson_ratio": 0.3, "friction_angle": 30.0, "cohesion": 5.0,
        "dilation_angle": 5.0, "tension_cutoff": 1.0}
CASES = {
    "2d-musl-linear-flip": scene(SCENE_2D),
    "2d-usl-quadratic-apic-j2": scene(SCENE_2D, method={"scheme": "usl", "shape_function": "quadratic_bspline",
                                                        "transfer": "apic"}, materials={"rubber": PLASTIC}),
    "3d-musl-linear-flip": scene(SCENE_3D),
    "2d-musl-gimp-flip": scene(SCENE_2D, method__shape_function="gimp"),
    "3d-musl-cpdi-tet4-flip": scene(SCENE_3D, method__shape_function="cpdi_tet4"),   # corners moved per thread block
    "2d-usl-cubic-apic": scene(SCENE_2D, method={"scheme": "usl", "shape_function": "cubic_bspline",
                                                 "transfer": "apic"}),
    "2d-usl-quadratic-mls": scene(SCENE_2D, method={"scheme": "usl", "shape_function": "quadratic_bspline",
                                                    "transfer": "mls"}),
    "2d-musl-cubic-mls": scene(SCENE_2D, method={"scheme": "musl", "shape_function": "cubic_bspline",
                                                 "transfer": "mls"}),
    "2d-tlmpm-quadratic-apic-rigid": TLMPM_2D,
    "axisymmetric-j2-billet": AXISYMMETRIC,
    "2d-musl-linear-flip-drucker-prager": scene(SCENE_2D, materials={"rubber": {**SOIL, "model": "drucker_prager"}}),
    "3d-musl-linear-flip-mohr-coulomb": scene(SCENE_3D, materials={"rubber": {**SOIL, "model": "mohr_coulomb"}}),
    "axisymmetric-drucker-prager-billet": scene(AXISYMMETRIC, materials__steel={
        "model": "drucker_prager", "density": 7800.0, "youngs_modulus": 200e9, "poisson_ratio": 0.3,
        "friction_angle": 20.0, "cohesion": 0.3e9, "dilation_angle": 10.0}),
    # a saturated column (solver/pore_fluid.py, general kernels; its own passes are serial)
    "2d-musl-linear-saturated-column": PORE_2D,
}
PLASTIC_CASES = ("j2", "drucker-prager", "mohr-coulomb")


def run_in_process(case: dict, threads: int):
    loaded = load_scene(scene(case, parallel={"processes": 1, "threads": threads}))
    sim = ExplicitMPM(loaded)
    assert sim.threads == threads == numba.get_num_threads()
    for _ in range(STEPS):
        sim.advance(case["time"]["dt"])
    order = np.argsort(sim.particles.id)
    out = {name: getattr(sim.particles, name)[order] for name in ("x", "v", "stress")}
    if "pore_pressure" in sim.particles.extra:
        out["pore_pressure"] = sim.particles.extra["pore_pressure"][order]
    return out, sim


@pytest.mark.parametrize("name", list(CASES))
def test_two_threads_give_the_one_thread_particles(name):
    one, _ = run_in_process(CASES[name], 1)
    two, sim = run_in_process(CASES[name], 2)
    assert sim.fused == fused.supports(sim.scene)       # the fused step where it applies, the general one elsewhere
    assert np.max(np.abs(one["stress"])) > 0
    for field in one:
        assert relative_difference(one[field], two[field]) <= TOLERANCE, field
    if any(model in name for model in PLASTIC_CASES):
        assert np.max(sim.particles.extra["plastic_strain"]) > 0   # the threaded return mapping ran


def test_two_processes_of_two_threads_give_the_single_process_particles(tmp_path):
    case = CASES["2d-musl-linear-flip"]
    runs = {}
    for processes, threads in ((1, 1), (2, 2)):
        out = tmp_path / f"k{processes}-t{threads}"
        settings = {"processes": processes, "threads": threads, "rebalance_every": 20}
        finished = run_cli(scene(case, parallel=settings), out, processes)
        assert finished.returncode == 0, finished.stderr
        runs[processes] = last_frame(out)
    assert runs[1]["step"] == runs[2]["step"] == STEPS
    for field in ("position", "velocity", "stress"):
        assert relative_difference(runs[1]["fields"][field], runs[2]["fields"][field]) <= TOLERANCE, field


def test_mpm_run_threads_option_sets_the_scenes_threads(tmp_path):
    case = scene(CASES["2d-musl-linear-flip"], time={"end": 0.005, "dt": 0.001})
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(case))
    done = subprocess.run([sys.executable, "-m", "solver", "run", str(path), "-o", str(tmp_path / "out"), "-t", "2",
                           "--progress", "none"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert read_scene(tmp_path / "out" / "result.h5")["parallel"]["threads"] == 2
    bad = subprocess.run([sys.executable, "-m", "solver", "run", str(path), "-t", "0"], capture_output=True, text=True)
    assert bad.returncode != 0 and "must be >= 1" in bad.stderr
