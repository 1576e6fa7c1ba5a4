"""E8: Taylor bar, OFHC copper at 190 m/s, axisymmetric ULMPM at a CI resolution.

Coarse on purpose (cell 0.4 mm, 2 x 2 particles per cell: 2413 particles). The bounds are
the review's own ULMPM result ([R] Table 6, "MPM": linear hat functions, 8 particles per
cell, MUSL): its deviations from the experiment are |dL| / L = 6.2 %, |dD| / D = 6.7 %,
|dW| / W = 11.9 %, and its eq. 6.19 error 0.08. A ULMPM run of this project must do at
least as well; benchmarks/taylor_bar.py records where it stands at finer resolutions.
"""
import pytest

from taylor_bar import END, EXPERIMENT, REVIEW, error_measure, measure, taylor_scene

CELL, PPC = 0.4e-3, 2


@pytest.fixture(scope="module")
def bar(tmp_path_factory):
    from mpm_cases import Case
    from solver import run
    return Case(run(taylor_scene(CELL, PPC), tmp_path_factory.mktemp("taylor")))


def test_the_bar_comes_to_rest(bar):
    assert bar.result.status == "complete"
    s = bar.series()
    # [R]: the kinetic energy is close to zero at ~63 us; at 80 us under 1 % of the impact's
    assert s["kinetic_energy"][-1] < 0.01 * s["kinetic_energy"][0]


def test_final_shape_against_the_experiment(bar):
    measured = measure(bar.frame(-1), CELL / PPC)
    review = REVIEW["MPM"]
    for key in ("L", "D", "W"):
        allowed = abs(review[key] - EXPERIMENT[key]) / EXPERIMENT[key]
        assert abs(measured[key] - EXPERIMENT[key]) / EXPERIMENT[key] <= allowed, key
    error = error_measure(measured)
    print(f"Taylor bar axisymmetric, cell {CELL * 1e3} mm: L {measured['L'] * 1e3:.2f} D {measured['D'] * 1e3:.2f} "
          f"W {measured['W'] * 1e3:.2f} mm, eq. 6.19 error {error:.3f}")
    assert error <= review["error"]


def test_the_bar_is_plastically_deformed_at_the_impact_face_only(bar):
    f = bar.frame(-1)["fields"]
    z, eps = f["position"][:, 1], f["plastic_strain"]
    # large strains at the face (the mushroom), the rear end stays nearly elastic
    assert eps[z < 1e-3].max() > 1.0
    assert eps[z > 14e-3].max() < 0.1
    assert END > 63e-6
