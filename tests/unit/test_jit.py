"""The parallel kernels' two forms (solver/jit.py): a run on one thread runs, and compiles,
only the serial twins, and they give the bits of the parallel forms on one thread."""
import json
import os
import subprocess
import sys
from pathlib import Path

import numba
import numpy as np
import pytest

from solver import jit
from solver.jit import ThreadedKernel, njit, prange
from solver.scene_checks import load_scene
from solver.stepper import ExplicitMPM

ROOT = Path(__file__).resolve().parents[2]


@njit(parallel=True)   # not cached: a kernel of the tests, not of the solver
def _doubled(values):
    out = np.empty_like(values)
    for i in prange(values.shape[0]):
        out[i] = 2.0 * values[i]
    return out


@pytest.fixture
def restore_threads():
    yield
    jit.use_threads(numba.get_num_threads())


def test_one_thread_runs_the_serial_twin_and_several_the_parallel_form(restore_threads):
    assert isinstance(_doubled, ThreadedKernel)
    values = np.arange(5.0)
    jit.use_threads(1)
    assert np.array_equal(_doubled(values), 2 * values)
    assert _doubled.serial.signatures and not _doubled.parallel.signatures
    jit.use_threads(2)
    assert np.array_equal(_doubled(values), 2 * values)
    assert _doubled.parallel.signatures


SCENE = {
    "dimension": 2, "grid": {"lower": [0, 0], "upper": [1, 1], "cell_size": 0.1},
    "materials": {"m": {"model": "neo_hookean", "density": 1000, "youngs_modulus": 1e6, "poisson_ratio": 0.3}},
    "bodies": [{"name": "b", "material": "m", "geometry": {"type": "sphere", "center": [0.5, 0.5], "radius": 0.2},
                "particles_per_cell": 2, "initial_velocity": [0.3, -0.1]}],
    "gravity": [0.0, -9.81], "time": {"end": 0.02, "dt": 1e-4}, "parallel": {"threads": 1},
}


@pytest.mark.parametrize("general", [False, True])
def test_the_serial_twins_give_the_parallel_forms_bits_on_one_thread(general, restore_threads):
    """Same blocks, same order: the twin differs from the parallel form only in who runs the loop."""
    twins = ExplicitMPM(load_scene(SCENE), general=general)
    parallel_forms = ExplicitMPM(load_scene(SCENE), general=general)
    assert twins.threads == numba.get_num_threads() == 1
    for _ in range(20):
        jit.use_threads(1)
        twins.advance(1e-4)
        jit.use_threads(2)   # numba still runs one thread: the parallel forms on one thread
        parallel_forms.advance(1e-4)
    for name in ("x", "v", "stress", "F"):
        assert np.array_equal(getattr(twins.particles, name), getattr(parallel_forms.particles, name)), name
    assert np.max(np.abs(twins.particles.stress)) > 0.0


_LOADED_FORMS = """
import gc, json, sys
from solver.jit import ThreadedKernel
from solver.runner import run
run(json.loads(sys.argv[1]), sys.argv[2])
kernels = [k for k in gc.get_objects() if isinstance(k, ThreadedKernel)]
print(json.dumps({"twins": sum(bool(k.serial.overloads) for k in kernels),
                  "parallel": sorted(k.__qualname__ for k in kernels if k.parallel.overloads)}))
"""


@pytest.mark.parametrize("method", [{}, {"shape_function": "gimp", "scheme": "usl"}])
def test_a_run_on_one_thread_loads_no_parallel_form(tmp_path, method):
    """Neither directly nor through another kernel: a twin's callees are twins, so a small run
    never waits on numba's parallel compiler (fused and general backends)."""
    scene = {**SCENE, "parallel": {}, "method": method, "time": {"end": 0.001, "dt": 1e-4}}
    done = subprocess.run([sys.executable, "-c", _LOADED_FORMS, json.dumps(scene), str(tmp_path)], cwd=ROOT,
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    loaded = json.loads(done.stdout.splitlines()[-1])
    assert loaded["parallel"] == [] and loaded["twins"] >= 5, loaded


_DIRECT_CALL = """
import json
import os
import numpy as np
from solver.jit import njit, prange

@njit(parallel=True)
def doubled(values):
    out = np.empty_like(values)
    for i in prange(values.shape[0]):
        out[i] = 2.0 * values[i]
    return out

doubled(np.arange(3.0))
print(json.dumps({"twin": bool(doubled.serial.signatures), "parallel": bool(doubled.parallel.signatures)}))
"""


@pytest.mark.parametrize("cores", [1, 2])
def test_a_kernel_called_outside_a_run_takes_the_form_of_the_process_s_cores(cores):
    """With one core (MPM_CORES=1: a service worker's share, a test worker's) the serial twin, with
    more the parallel form; use_threads(None) goes back to that."""
    environment = {**os.environ, "MPM_CORES": str(cores)}
    done = subprocess.run([sys.executable, "-c", _DIRECT_CALL], cwd=ROOT, env=environment, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert json.loads(done.stdout.splitlines()[-1]) == {"twin": cores == 1, "parallel": cores > 1}


def test_use_threads_none_restores_the_process_s_default(restore_threads):
    jit.use_threads(2)
    assert jit._runs.one_thread is False
    jit.use_threads(None)
    assert jit._runs.one_thread is jit._ONE_CORE
