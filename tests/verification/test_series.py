"""Per-body and boundary time series (output.series, solver/series.py) against exact references:
the centre of mass and momentum of a falling block, and the reaction of a floor under a column."""
import numpy as np
import pytest

from solver import run
from solver.results import read_series

E, NU, RHO, G = 1.0e6, 0.3, 1000.0, -9.81


def scene(bodies_box, grid_upper, end, dt, transfer="flip", boundary_conditions=(), energies=10):
    return {
        "dimension": 2, "method": {"transfer": transfer, **({"flip_ratio": 1.0} if transfer == "flip" else {})},
        "grid": {"lower": [0.0, 0.0], "upper": grid_upper, "cell_size": 0.025},
        "materials": {"m": {"model": "linear_elastic", "density": RHO, "youngs_modulus": E, "poisson_ratio": NU}},
        "bodies": [{"name": "block", "material": "m", "particles_per_cell": 2,
                    "geometry": {"type": "box", "lower": bodies_box[0], "upper": bodies_box[1]}}],
        "boundary_conditions": list(boundary_conditions), "gravity": [0.0, G],
        "time": {"end": end, "dt": dt},
        "output": {"frames": 2, "fields": ["position"], "energies": energies,
                   "series": ["momentum", "center_of_mass", "reactions"]},
    }


def test_the_centre_of_mass_of_a_falling_block_follows_half_g_t_squared(tmp_path):
    # Free fall: every node with mass gets v~ = v + g dt and the particles move with it, so
    # y_n = y0 + g dt^2 n (n + 1) / 2 = y0 + g t^2 / 2 + g dt t / 2: the exact parabola plus the
    # first-order offset of the explicit step; the momentum is M g t.
    dt = 5e-4
    result = run(scene(([0.4, 0.6], [0.6, 0.8]), [1.0, 1.0], end=0.2, dt=dt), tmp_path)
    s = read_series(result.result_path)
    t, y = s["time"], s["center_of_mass_block_y"]
    mass = RHO * 0.2 * 0.2
    np.testing.assert_allclose(y, 0.7 + 0.5 * G * t**2 + 0.5 * G * dt * t, rtol=0, atol=1e-12)
    assert np.all(np.abs(y - (0.7 + 0.5 * G * t**2)) <= 0.5 * abs(G) * dt * t + 1e-12)
    np.testing.assert_allclose(s["center_of_mass_block_x"], 0.5, rtol=0, atol=1e-12)
    np.testing.assert_allclose(s["momentum_block_y"], mass * G * t, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(s["momentum_block_x"], 0.0, atol=1e-12)
    # energy balance: kinetic (M/2) (g n dt)^2 against the work of gravity sum_k M g^2 dt^2 k =
    # M g^2 dt^2 n (n + 1) / 2: the explicit step's error is -M g^2 dt t / 2, first order in dt
    np.testing.assert_allclose(s["energy_error"], -0.5 * mass * G**2 * dt * t, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(s["energy_balance"], s["total_energy"] - s["external_work"] - s["boundary_work"],
                               rtol=1e-12, atol=1e-12)


def test_the_floor_under_a_column_carries_its_weight(tmp_path):
    # A column dropped onto a stick floor (gravity switched on at t = 0) oscillates and PIC
    # damps it. Momentum balance over each series interval T: R_floor T = M g T - (p_end - p_start)
    # holds to round-off (PIC: the particles' momentum is the grid's after the update); once the
    # column has settled, the floor's mean reaction is the weight M g.
    dt = 2.5e-4
    result = run(scene(([0.2, 0.0], [0.3, 0.3]), [0.5, 0.5], end=1.0, dt=dt, transfer="pic",
                       boundary_conditions=[{"type": "wall", "face": "y-", "mode": "stick"}], energies=100), tmp_path)
    s = read_series(result.result_path)
    weight = RHO * 0.1 * 0.3 * G
    t, p, reaction = s["time"], s["momentum_block_y"], s["reaction_bc0_y"]
    interval = np.diff(t)
    np.testing.assert_allclose(reaction[1:] * interval, weight * interval - np.diff(p), rtol=0,
                               atol=1e-9 * abs(weight) * interval.max())
    settled = t > 0.5
    mean = np.sum(reaction[settled] * np.r_[0.0, interval][settled]) / np.sum(np.r_[0.0, interval][settled])
    assert mean == pytest.approx(weight, rel=0.01)
    np.testing.assert_allclose(s["reaction_bc0_x"][1:], 0.0, atol=1e-6 * abs(weight))
