"""Solver processes started together on an empty kernel cache (solver/kernel_cache.py):
the first round compiles each kernel once between them (two of them run the same scene)
and saves at once into shared index files, the second round compiles nothing, reports
it, and computes the same bits."""
import json
import os
import subprocess
import sys


from tests.same_result import assert_same_result



def _tiny_1d(model: str, shape: str) -> dict:
    return {"version": 1, "name": f"{model} {shape}", "dimension": 1,
            "method": {"shape_function": shape},
            "grid": {"lower": [0.0], "upper": [1.0], "cell_size": 0.125},
            "materials": {"m": {"model": model, "density": 1000.0, "youngs_modulus": 1000.0,
                                "poisson_ratio": 0.3}},
            "bodies": [{"name": "b", "material": "m", "geometry": {"type": "box", "lower": [0.25], "upper": [0.75]},
                        "particles_per_cell": 2, "initial_velocity": [0.1]}],
            "time": {"end": 0.02, "dt": 0.001}, "output": {"frames": 3}}


SCENES = {"linear": _tiny_1d("linear_elastic", "linear"),
          "linear_again": _tiny_1d("linear_elastic", "linear"),
          "neo_hookean": _tiny_1d("neo_hookean", "linear"),
          "bspline": _tiny_1d("linear_elastic", "quadratic_bspline")}


def _round(tmp_path, cache, label: str) -> dict[str, dict]:
    """Start one solver process per scene at once; their `done` lines by scene."""
    env = dict(os.environ, MPM_CACHE_DIR=str(cache))
    processes = {}
    for name, scene in SCENES.items():
        path = tmp_path / f"{name}.json"
        path.write_text(json.dumps(scene))
        processes[name] = subprocess.Popen(
            [sys.executable, "-m", "solver", "run", str(path), "-o", str(tmp_path / label / name), "--progress", "json"],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    done = {}
    for name, process in processes.items():
        out, err = process.communicate(timeout=540)
        assert process.returncode == 0, err[-2000:]
        lines = [json.loads(line) for line in out.splitlines() if line.startswith("{")]
        done[name] = {"done": lines[-1], "stages": [line.get("stage") for line in lines[:-1]]}
    return done


def test_a_second_round_of_processes_compiles_nothing_and_computes_the_same_bits(tmp_path):
    cache = tmp_path / "cache"
    first = _round(tmp_path, cache, "first")
    for name, run in first.items():
        assert run["stages"][0] == "compiling" and "writing" in run["stages"], name
    # every compilation is saved as one entry: as many compilations as entries means none
    # was compiled by two processes (the one that waited loaded the other's)
    entries = len(list(cache.rglob("*.nbc")))
    assert sum(run["done"]["compiled"] for run in first.values()) == entries
    assert first["neo_hookean"]["done"]["compiled"] > 0   # its material's kernels are its own
    second = _round(tmp_path, cache, "second")
    for name, run in second.items():
        assert run["done"]["compiled"] == 0, (name, run["done"])
        assert_same_result(tmp_path / "first" / name / "result.h5", tmp_path / "second" / name / "result.h5")
    assert len(list(cache.glob("v-*"))) == 1   # one version: one folder
