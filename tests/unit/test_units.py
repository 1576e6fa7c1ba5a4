"""docs/units.md's claim: a scene in SI and the same scene in mm-ms-g (lengths x 1000, times
x 1000, densities / 10^6, moduli / 10^6, accelerations / 1000, velocities as they are) give
the same motion and stresses, scaled. The solver has no units; this checks that nothing in
it (an absolute tolerance, a hidden constant) assumes one."""
import numpy as np

from solver import run
from solver.results import read_frame

# SI: a steel block (c = 5048 m/s) at 10 m/s into a slip floor under gravity; dt = 0.2 h / c.
SI = {
    "dimension": 2,
    "grid": {"lower": [0.0, 0.0], "upper": [0.1, 0.1], "cell_size": 0.01},
    "materials": {"steel": {"model": "neo_hookean", "density": 7850.0, "youngs_modulus": 2e11,
                            "poisson_ratio": 0.3}},
    "bodies": [{"name": "block", "material": "steel", "initial_velocity": [3.0, -10.0],
                "geometry": {"type": "box", "lower": [0.02, 0.0], "upper": [0.06, 0.04]}}],
    "boundary_conditions": [{"type": "wall", "face": "y-", "mode": "slip"}],
    "gravity": [0.0, -9.81],
    "time": {"end": 4e-5, "dt": 4e-7},
    "output": {"frames": 2, "fields": ["position", "velocity", "stress"]},
    "units": {"length": "m", "time": "s", "mass": "kg", "stress": "Pa"},
}


def mm_ms_g(scene: dict) -> dict:
    """The same scene in mm, ms and g (force N, stress MPa): docs/units.md, second column."""
    scaled = {**scene, "grid": {"lower": [0.0, 0.0], "upper": [100.0, 100.0], "cell_size": 10.0},
              "gravity": [0.0, -9.81e-3], "time": {"end": 4e-2, "dt": 4e-4},
              "units": {"length": "mm", "time": "ms", "mass": "g", "stress": "MPa"}}
    scaled["materials"] = {"steel": {**scene["materials"]["steel"], "density": 7.85e-3, "youngs_modulus": 2e5}}
    scaled["bodies"] = [{**scene["bodies"][0],
                         "geometry": {"type": "box", "lower": [20.0, 0.0], "upper": [60.0, 40.0]}}]
    return scaled


def test_si_and_mm_ms_g_give_the_same_run(tmp_path):
    si = run(SI, tmp_path / "si")
    mm = run(mm_ms_g(SI), tmp_path / "mm")
    assert si.status == mm.status == "complete" and si.steps == mm.steps == 100
    a, b = (read_frame(result.result_path)["fields"] for result in (si, mm))
    order_a, order_b = np.argsort(a["id"]), np.argsort(b["id"])
    # The sets differ by powers of ten, which binary floating point does not scale exactly:
    # the runs agree to round-off grown over 100 steps, far below the motion (1e-4 m) and
    # the contact stresses (1e8 Pa) being compared.
    np.testing.assert_allclose(b["position"][order_b] * 1e-3, a["position"][order_a], rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(b["velocity"][order_b], a["velocity"][order_a], rtol=1e-9, atol=1e-10)  # measured: 2e-12
    stress_a = a["stress"][order_a]
    assert np.abs(stress_a).max() > 1e7  # the block has hit the floor: stresses to compare
    np.testing.assert_allclose(b["stress"][order_b] * 1e6, stress_a, rtol=1e-9, atol=1e-10 * np.abs(stress_a).max())  # measured: 4e-13 of the largest
