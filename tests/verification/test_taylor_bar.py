"""E8: Taylor bar, OFHC copper at 190 m/s, axisymmetric ULMPM at a CI resolution.

Coarse on purpose (cell 0.4 mm, 2 x 2 particles per cell: 2413 particles). The bounds are
the review's own ULMPM result ([R] Table 6, "MPM": linear hat functions, 8 particles per
cell, MUSL): its deviations from the experiment are |dL| / L = 6.2 %, |dD| / D = 6.7 %,
|dW| / W = 11.9 %, and its eq. 6.19 error 0.08. A ULMPM run of this project must do at
least as well; benchmarks/taylor_bar.py records where it stands at finer resolutions.

The same bar in axisymmetric TLMPM (the hoop terms in the reference configuration,
solver/axisymmetric.py) with the review's TLMPM discretisation, linear hats and one
particle per cell: at cell 0.4 mm here (603 particles), and at 0.2 mm (the ULMPM bar's
particle spacing and count) as a slow test. Each must be within the same bounds against
the experiment, and within two particle spacings of the ULMPM bar on L, D and W: each
measure is read off the outermost particles, so a run resolves it to about one spacing,
and a difference of two runs to two.
"""
import pytest

from mpm_cases import run_scene
from taylor_bar import END, EXPERIMENT, REVIEW, error_measure, measure, rough_anvil_scene, taylor_scene

CELL, PPC = 0.4e-3, 2


TLMPM_CELL, TLMPM_SLOW_CELL = 0.4e-3, 0.2e-3   # one particle per cell


def run_bar(tmp_path_factory, cell, ppc, formulation="ulmpm"):
    return run_scene(taylor_scene(cell, ppc, formulation=formulation), tmp_path_factory.mktemp("taylor"))


@pytest.fixture(scope="module")
def bar(tmp_path_factory):
    return run_bar(tmp_path_factory, CELL, PPC)


@pytest.fixture(scope="module")
def tlmpm_bar(tmp_path_factory):
    return run_bar(tmp_path_factory, TLMPM_CELL, 1, "tlmpm")


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


def check_tlmpm_bar(tl, ul, cell):
    """The TLMPM bar of cell `cell` (one particle per cell) against the experiment, with the
    ULMPM bar's bounds, and against the ULMPM bar `ul` (spacing CELL / PPC)."""
    assert tl.result.status == "complete"
    s = tl.series()
    assert s["kinetic_energy"][-1] < 0.01 * s["kinetic_energy"][0]
    measured, reference = measure(tl.frame(-1), cell), measure(ul.frame(-1), CELL / PPC)
    review = REVIEW["MPM"]
    print(f"Taylor bar axisymmetric TLMPM, cell {cell * 1e3} mm: L {measured['L'] * 1e3:.2f} "
          f"D {measured['D'] * 1e3:.2f} W {measured['W'] * 1e3:.2f} mm, eq. 6.19 error {error_measure(measured):.3f}")
    for key in ("L", "D", "W"):
        allowed = abs(review[key] - EXPERIMENT[key]) / EXPERIMENT[key]
        assert abs(measured[key] - EXPERIMENT[key]) / EXPERIMENT[key] <= allowed, key
        assert abs(measured[key] - reference[key]) <= 2 * max(cell, CELL / PPC), key
    assert error_measure(measured) <= review["error"]
    f = tl.frame(-1)["fields"]
    z, eps = f["position"][:, 1], f["plastic_strain"]
    assert eps[z < 1e-3].max() > 1.0 and eps[z > 14e-3].max() < 0.1


def test_tlmpm_bar_against_the_experiment_and_ulmpm(tlmpm_bar, bar):
    # measured: L 17.02, D 14.34, W 10.22 mm, error 0.042 (ULMPM's: 16.78, 13.82, 9.73, 0.032)
    check_tlmpm_bar(tlmpm_bar, bar, TLMPM_CELL)


@pytest.mark.slow
def test_tlmpm_bar_at_the_ulmpm_bars_spacing(tmp_path_factory, bar):
    # measured: L 17.00, D 13.82, W 9.75 mm, error 0.036 (the 3D quarter's TLMPM at 0.25 mm:
    # 17.00, 14.22, 10.11, 0.035; docs/benchmarks.md)
    check_tlmpm_bar(run_bar(tmp_path_factory, TLMPM_SLOW_CELL, 1, "tlmpm"), bar, TLMPM_SLOW_CELL)


def test_without_the_rate_term_the_bar_has_the_experiment_s_length(tmp_path):
    """The long bar is [R] Table 5's rate term C = 0.013: the review's authors ran this bar with
    C = 0 (their Karamelo input, data/karamelo: `C = 0#0.013`), where L comes within 2 % of the
    experiment (measured 16.20 mm at this cell, 16.07 at 0.1 mm) and the face 7-8 % wide
    (14.48 mm; [R] Table 6's own MPM: 14.4): the rate term trades the length for the diameter
    (docs/benchmarks.md, "Taylor bar")."""
    scene = taylor_scene(CELL, PPC)
    scene["materials"]["copper"] = {**scene["materials"]["copper"], "C": 0.0}
    case = run_scene(scene, tmp_path / "no-rate")
    assert case.result.status == "complete"
    m = measure(case.frame(-1), CELL / PPC)
    assert abs(m["L"] - EXPERIMENT["L"]) / EXPERIMENT["L"] <= 0.02
    assert m["D"] > 1.05 * EXPERIMENT["D"]


def check_within_two_percent(tmp_path, cell, dimension=2):
    case = run_scene(rough_anvil_scene(cell, dimension=dimension), tmp_path / "rough-anvil")
    assert case.result.status == "complete"
    m = measure(case.frame(-1), cell / PPC)
    deviations = {k: (m[k] - EXPERIMENT[k]) / EXPERIMENT[k] for k in ("L", "D", "W")}
    assert all(abs(d) <= 0.02 for d in deviations.values()), deviations


def test_on_a_rough_anvil_without_the_rate_term_l_d_and_w_are_within_two_percent(tmp_path):
    """The bar's two misfits have two causes: the rate term lengthens it (above), and the slip
    wall lets its face spread. With C = 0 and Coulomb friction 0.2 on the anvil, measured at this
    cell L +1.5 %, D -1.8 %, W -1.0 % (error 0.014; [R] Table 6's best, TLMPM, 0.03)."""
    check_within_two_percent(tmp_path, CELL)


@pytest.mark.slow
def test_on_a_rough_anvil_the_bar_stays_within_two_percent_at_a_quarter_of_the_cell(tmp_path):
    # measured at 0.2 / 0.1 mm: L +1.1 / +0.6 %, D -1.4 / -1.7 %, W -0.3 / -0.3 % (61 s at 0.1 mm)
    check_within_two_percent(tmp_path, CELL / 4)


@pytest.mark.slow
def test_the_3d_quarter_on_a_rough_anvil_is_within_two_percent(tmp_path):
    # measured at 0.4 mm (35,687 particles, 21 s): L +1.6 %, D -0.2 %, W +0.6 % (slip anvil: D +8.9 %)
    check_within_two_percent(tmp_path, CELL, dimension=3)
