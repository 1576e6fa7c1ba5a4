"""The helper that compiles a cold run's step from its other end (solver/precompile.py)."""
import json
import os
import subprocess
import sys

from solver import precompile
from service_support import bar_1d
from solver.scene_checks import load_scene

SCENE = {**bar_1d("helper", end=0.005, model="neo_hookean", particles_per_cell=3), "method": {"scheme": "musl"}}


def test_the_coarse_copy_keeps_the_scene_but_its_particle_counts_and_runs_on_the_run_s_threads():
    coarse = precompile.coarse(SCENE, 2)
    assert coarse["bodies"][0]["particles_per_cell"] == 1
    assert coarse["parallel"] == {"threads": 2}   # fewer particles would take fewer: other kernels
    assert {**coarse, "bodies": SCENE["bodies"], "parallel": SCENE.get("parallel", {})} == {**SCENE, "parallel": {}}
    assert load_scene(coarse).dimension == 1


def test_after_the_helper_a_run_compiles_almost_nothing(tmp_path):
    """The helper alone (run to its end here) compiles the step's phases and hooks; the run
    after it compiles only what lies outside the step (the output and the energy checks)."""
    env = dict(os.environ, MPM_CACHE_DIR=str(tmp_path / "cache"), MPM_PRECOMPILE="0")
    helper_scene = tmp_path / "coarse.json"
    helper_scene.write_text(json.dumps(precompile.coarse(SCENE, 1)))   # the run's threads: 1 for so few particles
    subprocess.run([sys.executable, "-m", "solver.precompile", str(helper_scene)], env=env, check=True, timeout=600)
    assert not helper_scene.exists()   # the helper removes its copy
    scene = tmp_path / "scene.json"
    scene.write_text(json.dumps(SCENE))
    done = subprocess.run([sys.executable, "-m", "solver", "run", str(scene), "-o", str(tmp_path / "out"),
                           "--progress", "json"], env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    final = json.loads(done.stdout.splitlines()[-1])
    cold = subprocess.run([sys.executable, "-m", "solver", "run", str(scene), "-o", str(tmp_path / "cold"),
                           "--progress", "json"], env=dict(env, MPM_CACHE_DIR=str(tmp_path / "empty")),
                          capture_output=True, text=True, timeout=600)
    everything = json.loads(cold.stdout.splitlines()[-1])["compiled"]
    assert final["compiled"] <= everything // 3, (final["compiled"], everything)


def _machine(monkeypatch, idle_now: float, load_average: float, cores: int = 2):
    """A machine of `cores` cores whose /proc/stat shows `idle_now` cores idle over the window
    and whose 1-minute load average is `load_average`; the scene's variant never compiled."""
    ticks = iter([(0, 0), (int(100 * idle_now), 100 * cores)])
    monkeypatch.setattr(precompile, "_cpu_ticks", lambda: next(ticks))
    monkeypatch.setattr(precompile, "IDLE_WINDOW", 0.0)
    monkeypatch.setattr(os, "cpu_count", lambda: cores)
    monkeypatch.setattr(os, "getloadavg", lambda: (load_average,) * 3)
    monkeypatch.setattr(precompile, "available_cores", lambda: cores)
    monkeypatch.setattr(precompile.cost, "is_compiled", lambda scene, threads: False)
    monkeypatch.delenv("MPM_PRECOMPILE", raising=False)


def test_a_run_right_after_a_busy_minute_gets_its_helper_when_a_core_is_idle_now(monkeypatch):
    """The load average trails by a minute: after a compile it says the machine is busy while a
    core sits idle (the gate used it, and back-to-back cold runs compiled alone)."""
    _machine(monkeypatch, idle_now=0.95, load_average=1.9)
    assert precompile.wanted(load_scene(SCENE), 1)


def test_no_helper_when_no_core_is_idle_now(monkeypatch):
    _machine(monkeypatch, idle_now=0.3, load_average=0.2)
    assert not precompile.wanted(load_scene(SCENE), 1)


def test_the_idle_cores_read_from_the_machine_are_within_its_cores():
    assert 0.0 <= precompile.idle_cores() <= (os.cpu_count() or 1) + 1e-9


def test_the_helper_reads_a_scene_that_names_a_file(tmp_path, monkeypatch):
    """A scene's mesh or points file is named by its absolute path once the run has validated
    it (the copy the helper gets): the helper reads it and builds the run's simulation."""
    (tmp_path / "cloud.csv").write_text("x,y,volume\n0.42,0.42,0.0025\n0.47,0.42,0.0025\n0.42,0.47,0.0025\n")
    scene = {"dimension": 2, "grid": {"lower": [0, 0], "upper": [1, 1], "cell_size": 0.1},
             "materials": {"m": {"model": "linear_elastic", "density": 1000, "youngs_modulus": 1e6,
                                 "poisson_ratio": 0.3}},
             "bodies": [{"name": "cloud", "material": "m", "geometry": {"type": "points", "file": "cloud.csv"}}],
             "time": {"end": 0.01}}
    (tmp_path / "scene.json").write_text(json.dumps(scene))
    validated = load_scene(tmp_path / "scene.json")
    copy = tmp_path / "helper" / "coarse.json"   # (precompile.start writes it to a temporary folder)
    copy.parent.mkdir()
    copy.write_text(json.dumps(precompile.coarse(validated.model_dump(mode="json", exclude_unset=True), 1)))
    built = []
    monkeypatch.setattr(precompile, "compile_backwards", lambda sim, dt: built.append(sim.particles.count))
    assert precompile.main(str(copy)) == 0 and built == [3]

