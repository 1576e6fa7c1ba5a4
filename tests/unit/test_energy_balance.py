"""The energy balance is a sum over registered terms (solver/energy.py)."""
import numpy as np

from solver import energy, run
from solver.results import read_series


def scene(**extra) -> dict:
    return {"dimension": 2, "grid": {"lower": [0, 0], "upper": [1, 1], "cell_size": 0.1},
            "materials": {"m": {"model": "linear_elastic", "density": 1000, "youngs_modulus": 1e4,
                                "poisson_ratio": 0.3}},
            "bodies": [{"name": "b", "material": "m", "initial_velocity": [0.1, 0.0],
                        "geometry": {"type": "box", "lower": [0.3, 0.3], "upper": [0.6, 0.6]}}],
            "time": {"end": 0.05, "dt": 1e-3}, "output": {"frames": 2, "fields": ["position"]}, **extra}


def test_a_registered_work_term_is_a_column_and_enters_the_balance(tmp_path, monkeypatch):
    # a made-up "heater" that has done work 1 J since t = 0 at every row: the balance drops by 1
    monkeypatch.setattr(energy, "TERMS", list(energy.TERMS))
    energy.register(energy.Term("heater_work", energy.WORK, lambda sim: 1.0))
    s = read_series(run(scene(), tmp_path / "a").result_path)
    assert np.all(s["heater_work"] == 1.0)
    stored = s["kinetic_energy"] + s["strain_energy"]
    np.testing.assert_array_equal(s["total_energy"], stored)
    np.testing.assert_allclose(s["energy_balance"], stored - s["external_work"] - s["boundary_work"] - 1.0,
                               rtol=1e-14, atol=1e-14)
    np.testing.assert_allclose(s["energy_error"], s["energy_balance"] - stored[0], rtol=1e-14, atol=1e-14)


def test_a_term_a_scene_does_not_have_is_no_column(tmp_path):
    s = read_series(run(scene(), tmp_path).result_path)
    assert "damping_work" not in s and {"energy_balance", "energy_error", "external_work"} <= set(s)
    s = read_series(run(scene(damping={"type": "viscous", "coefficient": 1.0}), tmp_path / "d").result_path)
    assert "damping_work" in s and s["damping_work"][-1] < 0
