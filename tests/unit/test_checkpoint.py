"""Restart checkpoints: a run stopped or crashed mid-way and resumed writes the same
result file as a run that was never interrupted.

The solver draws no random numbers and its kernels are serial, so a resumed run
performs the same floating-point operations in the same order on the same bits as
the uninterrupted one: the frames and time series must be equal bit for bit. Any
difference means some state was left out of the checkpoint (so the tests compare
with exact equality, not a tolerance)."""
import os
import signal
import subprocess
import sys
from pathlib import Path

import h5py
import pytest

from solver import run, runner
from solver.checkpoint import CHECKPOINT_FILE, CheckpointError
from solver.results import list_frames, read_series

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
from same_result import assert_same_result  # noqa: E402


def column(**output):
    """Gravity, a stick floor (boundary work), an adaptive time step and a
    body-force expression of the reference position (Particles.X is carried)."""
    return {
        "version": 1, "name": "column", "dimension": 2,
        "grid": {"lower": [0.0, 0.0], "upper": [0.6, 0.6], "cell_size": 0.05},
        "materials": {"m": {"model": "neo_hookean", "density": 1000.0, "youngs_modulus": 2.0e4,
                            "poisson_ratio": 0.3}},
        "bodies": [{"name": "b", "material": "m", "particles_per_cell": 2,
                    "geometry": {"type": "box", "lower": [0.2, 0.0], "upper": [0.4, 0.3]},
                    "initial_velocity": [0.1, 0.0]}],
        "boundary_conditions": [{"type": "wall", "face": "y-", "mode": "stick"}],
        "gravity": [0.0, -9.81],
        "body_force": ["0.5 * X * sin(20 * t)", "0"],
        "method": {"transfer": "flip", "flip_ratio": 0.99},
        "time": {"end": 0.5, "dt": None, "cfl": 0.4},
        "output": {"frames": 7, "fields": ["position", "velocity", "stress", "von_mises"],
                   "energies": 3, **output},
    }


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """The uninterrupted run."""
    out = tmp_path_factory.mktemp("reference")
    result = run(column(), out)
    assert result.status == "complete"
    assert not (out / CHECKPOINT_FILE).exists()  # a finished run leaves none behind
    return result


def stop_after(calls: int):
    count = 0

    def should_stop() -> bool:
        nonlocal count
        count += 1
        return count > calls
    return should_stop


def test_a_run_stopped_and_resumed_writes_the_same_result(reference, tmp_path, monkeypatch):
    monkeypatch.setattr(runner, "PROGRESS_INTERVAL_S", 0.0)  # poll should_stop every step
    stopped = run(column(), tmp_path, should_stop=stop_after(41))
    assert (stopped.status, stopped.reason) == ("partial", "cancelled")
    assert 0 < stopped.steps < reference.steps
    assert (tmp_path / CHECKPOINT_FILE).exists()

    resumed = run(column(), tmp_path, resume=True)
    assert (resumed.status, resumed.steps) == ("complete", reference.steps)
    assert_same_result(reference.result_path, resumed.result_path)
    assert not (tmp_path / CHECKPOINT_FILE).exists()


def test_a_run_stopped_twice_resumes_twice(reference, tmp_path, monkeypatch):
    monkeypatch.setattr(runner, "PROGRESS_INTERVAL_S", 0.0)
    run(column(), tmp_path, should_stop=stop_after(17))
    second = run(column(), tmp_path, should_stop=stop_after(30), resume=True)
    assert second.reason == "cancelled"
    run(column(), tmp_path, resume=True)
    assert_same_result(reference.result_path, tmp_path / "result.h5")


class Crash(Exception):
    pass


def test_a_crash_resumes_from_the_last_periodic_checkpoint(reference, tmp_path, monkeypatch):
    """A crash writes nothing more: the run goes on from the checkpoint of `every_steps`,
    redoing the steps after it, and frames written after it are dropped and written again."""
    monkeypatch.setattr(runner, "PROGRESS_INTERVAL_S", 0.0)
    scene = column(checkpoint={"every_steps": 25})

    def crash_at_step_60(info):
        if info.step >= 60:
            raise Crash

    with pytest.raises(Crash):
        run(scene, tmp_path, progress=crash_at_step_60)
    with h5py.File(tmp_path / CHECKPOINT_FILE, "r") as h5:
        assert h5.attrs["step"] == 50
    frames_before = len(list_frames(tmp_path / "result.h5"))

    resumed = run(scene, tmp_path, resume=True)
    assert frames_before > 0 and resumed.status == "complete"
    uninterrupted = run(scene, tmp_path / "uninterrupted")
    assert_same_result(uninterrupted.result_path, resumed.result_path)


def test_sigterm_writes_a_checkpoint_and_mpm_run_resume_finishes_the_run(tmp_path):
    """`mpm run` in its own process, stopped by SIGTERM, continued by `mpm run --resume DIR`
    (the scene read back from the checkpoint)."""
    import json
    scene_file = tmp_path / "scene.json"
    # two elastic disks between slip walls: stable however long, 10000 steps (about a second)
    disk = {"material": "m", "particles_per_cell": 2}
    boxed = {
        "version": 1, "name": "boxed", "dimension": 2,
        "grid": {"lower": [-0.5, -0.5], "upper": [0.5, 0.5], "cell_size": 0.05},
        "materials": {"m": {"model": "linear_elastic", "density": 1000, "youngs_modulus": 1000,
                            "poisson_ratio": 0.3}},
        "bodies": [{**disk, "name": "a", "geometry": {"type": "sphere", "center": [-0.2, -0.2], "radius": 0.15},
                    "initial_velocity": [0.1, 0.1]},
                   {**disk, "name": "b", "geometry": {"type": "sphere", "center": [0.2, 0.2], "radius": 0.15},
                    "initial_velocity": [-0.1, -0.1]}],
        "boundary_conditions": [{"type": "wall", "face": f, "mode": "slip"} for f in ("x-", "x+", "y-", "y+")],
        "time": {"end": 10.0, "dt": 0.001},
        "output": {"frames": 11, "fields": ["position", "velocity", "stress"]},
    }
    scene_file.write_text(json.dumps(boxed))
    out = tmp_path / "out"
    command = [sys.executable, "-m", "solver", "run", str(scene_file), "-o", str(out), "--progress", "json"]
    process = subprocess.Popen(command, stdout=subprocess.PIPE, text=True)
    for line in process.stdout:  # stepping (the signal handlers are in place): freeze it there
        if json.loads(line).get("step", 0) > 0:
            process.send_signal(signal.SIGSTOP)
            break
    assert json.loads(line)["step"] < 10000, "the run ended before the signal: make it longer"
    process.send_signal(signal.SIGTERM)
    process.send_signal(signal.SIGCONT)
    process.communicate(timeout=60)
    assert process.returncode == 3  # partial: cancelled
    assert (out / CHECKPOINT_FILE).exists()

    done = subprocess.run([sys.executable, "-m", "solver", "run", "--resume", str(out), "--progress", "none"],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    uninterrupted = run(boxed, tmp_path / "uninterrupted")
    assert_same_result(uninterrupted.result_path, out / "result.h5")


def test_resume_refuses_a_checkpoint_of_another_scene(tmp_path, monkeypatch):
    monkeypatch.setattr(runner, "PROGRESS_INTERVAL_S", 0.0)
    run(column(), tmp_path, should_stop=stop_after(5))
    other = column()
    other["gravity"] = [0.0, -1.0]
    with pytest.raises(CheckpointError, match="another scene"):
        run(other, tmp_path, resume=True)


def test_resume_without_a_checkpoint_starts_from_the_beginning(reference, tmp_path):
    result = run(column(), tmp_path, resume=True)
    assert_same_result(reference.result_path, result.result_path)


def test_an_unreadable_result_file_makes_the_resume_start_again(reference, tmp_path, monkeypatch):
    monkeypatch.setattr(runner, "PROGRESS_INTERVAL_S", 0.0)
    run(column(), tmp_path, should_stop=stop_after(41))
    (tmp_path / "result.h5").write_bytes(b"not hdf5")
    result = run(column(), tmp_path, resume=True)
    assert_same_result(reference.result_path, result.result_path)


def test_the_checkpoint_interval_is_validated():
    from solver.scene import SceneError
    from solver.scene_checks import load_scene
    with pytest.raises(SceneError) as error:
        load_scene(column(checkpoint={}))
    assert error.value.errors[0]["path"] == "output.checkpoint"
    with pytest.raises(SceneError) as error:
        load_scene(column(checkpoint={"every_steps": 0}))
    assert error.value.errors[0]["path"] == "output.checkpoint.every_steps"


def test_the_checkpoint_replaces_the_previous_one_atomically(tmp_path, monkeypatch):
    """Written to a temporary file and renamed: the folder never holds a half-written one."""
    monkeypatch.setattr(runner, "PROGRESS_INTERVAL_S", 0.0)
    replaced = []
    real_replace = os.replace

    def spy(src, dst):
        replaced.append((os.path.basename(src), os.path.basename(dst)))
        real_replace(src, dst)
    monkeypatch.setattr(os, "replace", spy)
    run(column(checkpoint={"every_steps": 40}), tmp_path, should_stop=stop_after(90))
    saves = [pair for pair in replaced if pair[1] == CHECKPOINT_FILE]
    assert len(saves) == 3  # steps 40 and 80, and where it stopped
    assert all(src.startswith(".") and src.endswith(".tmp") for src, _ in saves)


def assert_resumes_alike(scene, tmp_path, monkeypatch):
    """A run stopped after 41 progress calls and resumed gives the uninterrupted run's
    result; returns the uninterrupted run's."""
    reference = run(scene, tmp_path / "reference")
    monkeypatch.setattr(runner, "PROGRESS_INTERVAL_S", 0.0)
    stopped = run(scene, tmp_path / "resumed", should_stop=stop_after(41))
    assert stopped.status == "partial" and stopped.reason == "cancelled"
    resumed = run(scene, tmp_path / "resumed", resume=True)
    assert resumed.steps == reference.steps
    assert_same_result(reference.result_path, resumed.result_path)
    return reference


def test_a_conducting_run_resumes_to_the_same_temperatures_and_boundary_heat(tmp_path, monkeypatch):
    """The thermal state (temperature, heat flux, the heat that came in) is carried."""
    scene = column()
    scene["materials"]["m"].update(thermal_conductivity=50.0, specific_heat=100.0, thermal_expansion=1e-4)
    scene["boundary_conditions"] += [{"type": "heat_flux", "face": "y-", "flux": 1.0e3},
                                     {"type": "temperature", "where": {"type": "box", "lower": [0.0, 0.25],
                                                                       "upper": [0.6, 0.6]},
                                      "temperature": "300 + 100 * t"}]
    scene["output"]["fields"] += ["temperature", "heat_flux"]
    assert_resumes_alike(scene, tmp_path, monkeypatch)


def test_a_saturated_run_resumes_to_the_same_pore_pressures(tmp_path, monkeypatch):
    """The pore pressure and Darcy flux of a saturated soil (solver/pore_fluid.py) are carried."""
    scene = column()
    scene["materials"]["m"]["pore_fluid"] = {"bulk_modulus": 1.0e5, "density": 1000.0,
                                             "hydraulic_conductivity": 1.0e-3, "porosity": 0.5}
    scene["bodies"][0]["initial_pore_pressure"] = {"type": "hydrostatic", "water_table": 0.3}
    scene["boundary_conditions"].append({"type": "pore_pressure", "pressure": 0.0,
                                         "where": {"type": "box", "lower": [0.0, 0.29], "upper": [0.6, 0.31]}})
    scene["output"]["fields"] += ["pore_pressure", "effective_stress"]
    assert_resumes_alike(scene, tmp_path, monkeypatch)


def test_a_run_with_a_tool_resumes_to_the_same_result(tmp_path, monkeypatch):
    """A tool's displacement, its reaction impulses since the last row and its work are
    carried by the checkpoint (solver/tools.py): the resumed run's frames and series
    (reaction_press_<axis>, tool_work) are the uninterrupted run's."""
    scene = column()
    scene["tools"] = [{"name": "press", "geometry": {"type": "box", "lower": [0.25, 0.29], "upper": [0.35, 0.4]},
                       "velocity": [0.0, "-0.2 * t"], "stiffness": 2.0, "friction": 0.2}]
    reference = assert_resumes_alike(scene, tmp_path, monkeypatch)
    series = read_series(reference.result_path)
    assert series["reaction_press_y"].max() > 0 and series["tool_work"][-1] != 0   # the tool did push


def test_a_run_on_a_frictional_floor_resumes_to_the_same_friction_work(tmp_path, monkeypatch):
    """The friction's work is carried (it was left out: a resumed run's friction_work started
    again from zero, and its energy_error jumped by what the friction had taken). A stiffer
    column than the others': the soft one on this floor stops as unstable with FLIP at cfl 0.4."""
    scene = column()
    scene["materials"]["m"]["youngs_modulus"] = 2.0e6
    scene["boundary_conditions"] = [{"type": "wall", "face": "y-", "mode": "friction", "friction": 0.3}]
    reference = assert_resumes_alike(scene, tmp_path, monkeypatch)
    assert read_series(reference.result_path)["friction_work"][-1] < 0   # the floor took energy out


def test_a_gas_run_resumes_to_the_same_result(tmp_path, monkeypatch):
    """A gas that takes its density from the grid (solver/gas_density.py): the energy it moved
    (gas_density_work) is carried, and the first resumed step takes the grid's density from
    the checkpoint's positions as the uninterrupted run did. Its sound speed, which sets the
    next time step, is carried too: a resumed run took the gas's initial one and ran 102 steps
    where the uninterrupted run took 103 (every material whose wave speed follows its state)."""
    tube = {"version": 1, "name": "tube", "dimension": 1, "method": {"shape_function": "linear"},
            "grid": {"lower": [0.0], "upper": [1.0], "cell_size": 0.01},
            "materials": {"air": {"model": "ideal_gas"}},
            "bodies": [{"name": "left", "material": "air", "particles_per_cell": 3, "initial_density": 1.0,
                        "initial_pressure": 1.0, "geometry": {"type": "box", "lower": [0.0], "upper": [0.5]}},
                       {"name": "right", "material": "air", "particles_per_cell": 3, "initial_density": 0.125,
                        "initial_pressure": 0.1, "geometry": {"type": "box", "lower": [0.5], "upper": [1.0]}}],
            "boundary_conditions": [{"type": "wall", "face": "x-", "mode": "slip"},
                                    {"type": "wall", "face": "x+", "mode": "slip"}],
            "time": {"end": 0.2, "cfl": 0.5},
            "output": {"frames": 5, "fields": ["position", "velocity", "density", "pressure"], "energies": True}}
    reference = assert_resumes_alike(tube, tmp_path, monkeypatch)
    assert read_series(reference.result_path)["gas_density_work"][-1] != 0
