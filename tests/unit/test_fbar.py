"""F-bar's kernels (solver/fbar.py) on hand-made particles: Algorithm 7 of the review."""
import numpy as np
import pytest

from solver.fbar import apply_fbar, cell_sums


def _two_cells():
    """Three particles in cell (0, 0) and one in cell (1, 0) of a 2 x 1 grid of h = 1, and a
    massless (rigid) particle; each with its own F."""
    x = np.array([[0.2, 0.3], [0.7, 0.8], [0.5, 0.5], [1.5, 0.5], [0.4, 0.4]])
    F = np.array([[[1.1, 0.1], [0.0, 1.0]], [[0.9, 0.0], [0.2, 0.95]], [[1.0, 0.0], [0.0, 1.02]],
                  [[1.2, 0.0], [0.0, 0.9]], [[1.0, 0.0], [0.0, 1.0]]])
    volume0 = np.array([1.0, 2.0, 1.5, 1.0, 1.0])
    J = np.linalg.det(F)
    mass = np.array([1.0, 1.0, 1.0, 1.0, 0.0])
    return x, F, volume0, J * volume0, mass


def test_cell_jacobian_is_the_volume_weighted_mean_and_each_particle_keeps_its_shape():
    x, F, volume0, volume, mass = _two_cells()
    strides = np.array([1, 3])                     # 3 x 2 nodes
    cell = np.empty(5, dtype=np.int64)
    vol0_cell, vol_cell = np.zeros(6), np.zeros(6)
    cell_sums(x, np.zeros(2), np.ones(2), np.array([2, 1]), strides, 0, mass, volume, volume0, cell,
              vol0_cell, vol_cell)
    assert cell.tolist() == [0, 0, 0, 1, -1]        # lower-corner nodes; the massless one skipped
    J = volume / volume0
    J_cell0 = (volume0[:3] * J[:3]).sum() / volume0[:3].sum()      # eq. 5.17
    L = np.zeros((5, 2, 2))
    log_ratio = np.zeros(5)
    F_bar = F.copy()
    V_bar = volume.copy()
    dt = 0.01
    apply_fbar(cell, vol0_cell, vol_cell, dt, F_bar, L, V_bar, volume0, log_ratio, 2)
    np.testing.assert_allclose(np.linalg.det(F_bar[:3]), J_cell0, rtol=1e-14)
    np.testing.assert_allclose(np.linalg.det(F_bar[3]), J[3], rtol=1e-14)   # alone in its cell
    np.testing.assert_allclose(V_bar[:3], J_cell0 * volume0[:3], rtol=1e-14)
    for p in range(4):   # F_bar = (J_c / J_p)^(1/2) F_p: the isochoric part is the particle's own
        np.testing.assert_allclose(F_bar[p] / np.sqrt(np.linalg.det(F_bar[p])), F[p] / np.sqrt(J[p]), rtol=1e-13)
    np.testing.assert_array_equal(F_bar[4], F[4])
    # L_bar = L + (1/d) d/dt ln(J_c / J_p) I, from the ratio 0 at the start
    np.testing.assert_allclose(L[:3, 0, 0], np.log(J_cell0 / J[:3]) / (2 * dt), rtol=1e-13)
    np.testing.assert_allclose(L[:, 0, 0], L[:, 1, 1])
    assert np.all(L[:, 0, 1] == 0) and L[3, 0, 0] == 0 and L[4, 0, 0] == 0
    np.testing.assert_allclose(log_ratio[:3], np.log(J_cell0 / J[:3]), rtol=1e-14)


def test_fbar_is_a_strict_boolean_off_by_default():
    from solver.scene import SceneError
    from solver.scene_checks import load_scene
    scene = {"version": 1, "name": "s", "dimension": 2, "grid": {"lower": [0, 0], "upper": [1, 1], "cell_size": 0.25},
             "materials": {"m": {"model": "linear_elastic", "density": 1, "youngs_modulus": 1, "poisson_ratio": 0.3}},
             "bodies": [{"name": "b", "material": "m", "geometry": {"type": "box", "lower": [0.25, 0.25],
                                                                   "upper": [0.5, 0.5]}}],
             "time": {"end": 1.0}}
    assert load_scene(scene).method.fbar is False
    scene["method"] = {"fbar": "yes"}
    with pytest.raises(SceneError) as error:
        load_scene(scene)
    assert [e["path"] for e in error.value.errors] == ["method.fbar"]


def test_a_run_with_fbar_and_cpdi_stopped_and_resumed_writes_the_same_result(tmp_path, monkeypatch):
    """F-bar's last ratio ln(J_c / J_p) and CPDI's domains are per-particle state: a resumed
    run must carry them (bit-for-bit, as tests/unit/test_checkpoint.py explains)."""
    from test_checkpoint import assert_same_result, column, stop_after   # (it puts tests/ on the path)

    from solver import run, runner
    scene = column()
    scene["method"].update(fbar=True, shape_function="cpdi_r4")
    reference = run(scene, tmp_path / "reference")
    assert reference.status == "complete"
    monkeypatch.setattr(runner, "PROGRESS_INTERVAL_S", 0.0)
    stopped = run(scene, tmp_path / "resumed", should_stop=stop_after(41))
    assert stopped.status == "partial"
    resumed = run(scene, tmp_path / "resumed", resume=True)
    assert (resumed.status, resumed.steps) == ("complete", reference.steps)
    assert_same_result(reference.result_path, resumed.result_path)
