"""The run loop: time steps, boundary conditions, loads, instability detection and stopping."""
import math

import h5py
import numpy as np
import pytest

from solver import run
from solver.results import list_frames, read_frame, read_series

E, NU, RHO = 1.0e4, 0.3, 1000.0
C_DIL = math.sqrt(E * (1 - NU) / ((1 + NU) * (1 - 2 * NU)) / RHO)


def block(dim=2, velocity=None, **extra):
    scene = {
        "version": 1, "name": "block", "dimension": dim,
        "grid": {"lower": [-1.0] * dim, "upper": [1.0] * dim, "cell_size": 0.1},
        "materials": {"m": {"model": "linear_elastic", "density": RHO, "youngs_modulus": E, "poisson_ratio": NU}},
        "bodies": [{"name": "b", "material": "m", "particles_per_cell": 2,
                    "geometry": {"type": "box", "lower": [-0.3] * dim, "upper": [0.3] * dim},
                    "initial_velocity": velocity or [0.0] * dim}],
        "time": {"end": 0.1, "dt": 1e-3},
        "output": {"frames": 3, "fields": ["position", "velocity", "stress"]},
    }
    scene.update(extra)
    return scene


def test_adaptive_time_step_follows_the_cfl_formula(tmp_path):
    scene = block(velocity=[0.5, -0.2], time={"end": 0.05, "dt": None, "cfl": 0.4})
    result = run(scene, tmp_path)
    assert result.status == "complete"
    dt = read_series(result.result_path)["dt"][0]
    # review eq. 2.73: dt = cfl * min_i h_i / (c_dil + max |v_i|); the slowest axis limits it here
    assert dt == pytest.approx(0.4 * 0.1 / (C_DIL + 0.5), rel=1e-12)
    assert result.time == pytest.approx(0.05, abs=1e-12)


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_smallest_stretch_is_the_smallest_singular_value_of_F(dim):
    """The closed forms (2D quadratic, 3D trigonometric cubic) against numpy's SVD, for F near
    the identity, strongly stretched and sheared, and a rotation times a squash."""
    from solver.tlmpm import smallest_stretch
    rng = np.random.default_rng(dim)
    for scale in (1e-6, 0.1, 1.0):
        F = np.eye(dim)[None] + scale * rng.normal(size=(200, dim, dim))
        F = F[np.linalg.det(F) > 1e-2]
        expected = np.linalg.svd(F, compute_uv=False)[:, -1]
        got = [smallest_stretch(F[p:p + 1]) for p in range(len(F))]
        np.testing.assert_allclose(got, expected, rtol=1e-8)   # the cubic's acos loses a few digits
        assert smallest_stretch(F) == pytest.approx(expected.min(), rel=1e-8)


def test_tlmpm_time_step_shrinks_with_the_smallest_stretch(tmp_path):
    """TLMPM's cells deform with the body: a particle squashed to 0.2 of its reference size
    along x takes the updated-Lagrangian step times 0.2 (a stretch above 1 leaves it)."""
    from solver.scene_checks import load_scene
    from solver.stepper import ExplicitMPM
    sim = ExplicitMPM(load_scene(block(method={"formulation": "tlmpm"}, time={"end": 0.05, "dt": None})))
    unstrained = sim.stable_time_step(0.5)
    assert unstrained == pytest.approx(0.5 * 0.1 / C_DIL, rel=1e-12)
    sim.particles.F[3] = [[0.2, 0.0], [0.0, 5.0]]
    assert sim.stable_time_step(0.5) == pytest.approx(0.2 * unstrained, rel=1e-12)
    sim.particles.F[3] = [[1.5, 0.0], [0.0, 2.0]]
    assert sim.stable_time_step(0.5) == pytest.approx(unstrained, rel=1e-12)


def test_frames_are_evenly_spaced_including_first_and_last(tmp_path):
    result = run(block(time={"end": 0.1, "dt": 0.003}, output={"frames": 5, "fields": ["position"]}), tmp_path)
    times = [f["time"] for f in list_frames(result.result_path)]
    np.testing.assert_allclose(times, np.linspace(0.0, 0.1, 5), atol=1e-12)


def test_slip_floor_stops_normal_motion_and_lets_the_body_slide(tmp_path):
    # a block sliding along a slip floor it rests on: the normal velocity is held at zero, the tangential kept
    scene = block(velocity=[0.2, 0.0], gravity=[0.0, -9.81],
                  boundary_conditions=[{"type": "wall", "face": "y-", "mode": "slip"}],
                  grid={"lower": [-1.0, -0.3], "upper": [1.0, 1.0], "cell_size": 0.1},
                  time={"end": 0.2, "dt": 2e-4})
    result = run(scene, tmp_path)
    last = read_frame(result.result_path)["fields"]
    bottom = last["position"][:, 1] < -0.25
    assert last["position"][:, 1].min() > -0.3 - 0.01          # did not fall through the floor
    assert np.mean(last["velocity"][bottom, 0]) == pytest.approx(0.2, rel=0.02)   # slides freely


def test_stick_floor_holds_the_bottom_of_the_body(tmp_path):
    scene = block(velocity=[0.2, 0.0],
                  boundary_conditions=[{"type": "wall", "face": "y-", "mode": "stick"}],
                  grid={"lower": [-1.0, -0.3], "upper": [1.0, 1.0], "cell_size": 0.1},
                  time={"end": 0.05, "dt": 2e-4})
    result = run(scene, tmp_path)
    first, last = read_frame(result.result_path, 0)["fields"], read_frame(result.result_path)["fields"]
    bottom = first["position"][:, 1] < -0.27
    order = np.argsort(last["id"])
    moved = last["position"][order][bottom] - first["position"][bottom]
    top = first["position"][:, 1] > 0.27
    assert np.abs(moved[:, 0]).max() < 0.5 * np.abs(last["position"][order][top, 0] - first["position"][top, 0]).mean()


def test_prescribed_velocity_expression_in_time_moves_the_constrained_nodes(tmp_path):
    # the whole grid is constrained to v = (0.3 t, 0): every particle must follow x = x0 + 0.15 t^2
    scene = block(boundary_conditions=[{"type": "velocity", "where": {"type": "box", "lower": [-2, -2], "upper": [2, 2]},
                                        "velocity": ["0.3 * t", 0.0]}],
                  time={"end": 0.2, "dt": 1e-3})
    result = run(scene, tmp_path)
    first, last = read_frame(result.result_path, 0)["fields"], read_frame(result.result_path)["fields"]
    dx = last["position"][np.argsort(last["id"]), 0] - first["position"][:, 0]
    t, dt = 0.2, 1e-3
    # x advances with the node velocity at the end of each step: sum of 0.3 (n dt) dt
    n = round(t / dt)
    assert dx == pytest.approx(np.full_like(dx, 0.3 * dt * dt * n * (n + 1) / 2), rel=1e-9)


def test_body_force_expression_equals_the_same_gravity(tmp_path):
    a = run(block(gravity=[0.0, -2.0]), tmp_path / "gravity")
    b = run(block(body_force=["0", "-2 + 0 * x"]), tmp_path / "expression")
    pa, pb = read_frame(a.result_path)["fields"]["position"], read_frame(b.result_path)["fields"]["position"]
    np.testing.assert_allclose(pa, pb, atol=1e-14)


def test_too_large_a_time_step_is_stopped_with_a_diagnostic(tmp_path):
    # dt forty times the stable step: the run must stop, name the step and the quantity, keep frames
    dt = 40 * 0.1 / C_DIL
    scene = block(velocity=["0.5 * x", "-0.5 * y"], time={"end": 200 * dt, "dt": dt, "allow_unstable_dt": True},
                  output={"frames": 100, "fields": ["position", "velocity"]})
    result = run(scene, tmp_path)
    assert result.status == "partial" and result.reason == "unstable"
    assert "unstable at step" in result.message
    assert any(q in result.message for q in ("energy", "J = det F", "position", "not finite", "left the grid"))
    with h5py.File(result.result_path) as h5:
        assert h5.attrs["status"] == "partial"
    assert len(list_frames(result.result_path)) >= 1
    assert result.steps < 200


def test_a_particle_leaving_the_grid_is_named(tmp_path):
    scene = block(velocity=[5.0, 0.0], time={"end": 1.0, "dt": 1e-3})
    result = run(scene, tmp_path)
    assert result.reason == "unstable"
    assert "left the grid" in result.message and "particle" in result.message


def test_should_stop_ends_the_run_as_partial(tmp_path):
    calls = []

    def stop():
        calls.append(1)
        return True

    scene = block(time={"end": 50.0, "dt": 1e-4})
    result = run(scene, tmp_path, should_stop=stop)
    assert calls and result.status == "partial" and result.reason == "cancelled"
    assert result.time < 50.0
    with h5py.File(result.result_path) as h5:
        assert h5.attrs["status"] == "partial"


def test_tlmpm_translates_a_free_body_rigidly_without_reference_body_forces(tmp_path):
    """TLMPM takes its weights at the reference positions X_p, which exist whether or
    not a body force is written in X, Y, Z: a free block moving at constant velocity
    keeps its velocity and moves by v t (no stress arises in a rigid translation)."""
    velocity = [0.3, -0.1]
    scene = block(velocity=velocity, method={"formulation": "tlmpm"}, time={"end": 0.05, "dt": 1e-3})
    result = run(scene, tmp_path)
    assert result.status == "complete"
    first, last = read_frame(result.result_path, 0), read_frame(result.result_path, -1)
    np.testing.assert_allclose(last["fields"]["velocity"], np.tile(velocity, (result.particles, 1)), atol=1e-12)
    np.testing.assert_allclose(last["fields"]["position"] - first["fields"]["position"],
                               np.tile(np.multiply(velocity, 0.05), (result.particles, 1)), atol=1e-12)


_SIGNALLED_WHILE_WRITING = """
import json, os, signal, sys
import solver.preview
from solver import run
outputs = solver.preview.finish_outputs
def signalled_while_writing(*args):
    os.kill(os.getpid(), signal.SIGTERM)   # a rank's own stop signal, after the ranks stopped together
    return outputs(*args)
solver.preview.finish_outputs = signalled_while_writing
result = run(json.loads(sys.argv[1]), sys.argv[2], should_stop=lambda: True)
print(result.reason, "and alive")
"""


def test_a_stop_signal_while_a_stopped_run_writes_its_outputs_does_not_end_it(tmp_path):
    """A run stopped on request (as a rank is when another rank's signal stopped them all) that
    gets a SIGTERM of its own while it writes its outputs finishes them: the signal reached
    one rank of a preempted Slurm job after the ranks had stopped, and killed it (and MPI's
    launcher the other) before rank 0 had written the checkpoint."""
    import json
    import subprocess
    import sys

    scene = block(dim=1, time={"end": 100.0, "dt": 1e-3})
    done = subprocess.run([sys.executable, "-c", _SIGNALLED_WHILE_WRITING, json.dumps(scene), str(tmp_path / "out")],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip().endswith("cancelled and alive")
    assert (tmp_path / "out" / "preview.png").exists()


@pytest.mark.parametrize("stopped", [False, True])
def test_a_run_gives_the_signal_handlers_back(tmp_path, stopped):
    """Stopped by a signal (Ctrl-C in a notebook) or not, run() leaves its caller's handlers as
    it found them: a notebook's next Ctrl-C interrupts as before."""
    import os
    import signal

    def interrupt(info):
        if stopped and info.stage == "stepping":
            os.kill(os.getpid(), signal.SIGINT)   # run()'s handler: a flag, the step in flight finishes

    before = signal.getsignal(signal.SIGTERM), signal.getsignal(signal.SIGINT)
    scene = block(time={"end": 100.0 if stopped else 0.002, "dt": 1e-3})
    result = run(scene, tmp_path / "out", progress=interrupt)
    assert result.reason == ("cancelled" if stopped else "finished")
    assert (signal.getsignal(signal.SIGTERM), signal.getsignal(signal.SIGINT)) == before
