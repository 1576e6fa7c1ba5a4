"""E4: Sod's shock tube ([R] 6.1.4), ideal gas, 400 cells, 3 particles per cell, MUSL.

Reference: the exact Riemann solution (exact_riemann.py): p* = 0.30313,
u* = 0.92745, rho*_L = 0.42632, rho*_R = 0.26557, shock speed 1.75216
(VERIFICATION_CASES E4). Compared at t = 0.2, when the shock is at 0.8504.

The scene is examples/sod_shock_tube.json: cubic B-splines at the default cfl 0.5.
With linear hats the particles' volumes (J V0) drift away from their spacing in the
expanded gas (1.2-1.5 particles per cell, cell-crossing), which needed cfl 0.025
and still left the left plateau 6 % low; with the C1 splines the volumes follow the
particles and the plateaus are within 1 % at cfl 0.5 (docs/benchmarks.md, issue 18).
"""
import json

import numpy as np
import pytest
from exact_riemann import SOD_LEFT, SOD_RIGHT, solve
from mpm_cases import run_scene

from solver.examples import DEFAULT_DIR

X0, END, CELLS = 0.5, 0.2, 400
H = 1.0 / CELLS
EXACT = solve(SOD_LEFT, SOD_RIGHT, gamma=1.4)


def sod_scene(artificial_viscosity=True):
    scene = json.loads((DEFAULT_DIR / "sod_shock_tube.json").read_text())
    assert scene["time"]["end"] == END and len(scene["bodies"]) == 2
    if not artificial_viscosity:
        scene["materials"]["air"]["artificial_viscosity"] = {"quadratic": 0.0, "linear": 0.0}
    scene["output"] = {"frames": 2, "fields": ["position", "velocity", "density", "pressure"]}
    return scene


def profiles(case):
    frame = case.frame(-1)
    f = frame["fields"]
    order = np.argsort(f["position"][:, 0])
    x = f["position"][order, 0]
    return frame["time"], x, f["density"][order], f["velocity"][order, 0], f["pressure"][order], f["body"][order]


@pytest.fixture(scope="module")
def with_av(tmp_path_factory):
    return run_scene(sod_scene(True), tmp_path_factory.mktemp("sod") / "av")


def test_runs_to_the_end(with_av):
    t, *_ = profiles(with_av)
    assert with_av.result.status == "complete"
    assert t == pytest.approx(END, abs=1e-12)


def test_l1_density_error_with_artificial_viscosity(with_av):
    t, x, rho, u, p, body = profiles(with_av)
    exact_rho, _, _ = EXACT.sample(x, t, X0)
    # Each particle stands for a length 1/1200 of the tube (the tube has length 1).
    l1 = np.mean(np.abs(rho - exact_rho))
    # The bound, from what a first-order Lagrangian scheme may get wrong (h = 1/400):
    # - shock smeared by the viscosity over 4 cells: a ramp of height
    #   drho = 0.2656 - 0.125 over 4h costs drho * 4h / 4 = 3.5e-4;
    # - the contact is a particle boundary (Lagrangian), it does not smear;
    # - the two plateaus within 5% (test_plateaus_within_five_percent):
    #   0.05 * (0.4263 * 0.1995 + 0.2656 * 0.1649) = 0.0064
    #   (plateau widths at t = 0.2: 0.4861 .. 0.6855 and 0.6855 .. 0.8504);
    # - the rarefaction (width 0.2226, mean density ~0.7) within 5%: 0.0078.
    # Sum: 0.0146, within the goal of 0.015 at cfl 0.5. Without viscosity the
    # oscillations behind the shock exceed it (0.019, docs/benchmarks.md).
    assert l1 < 0.0146


def test_plateaus_within_five_percent(with_av):
    t, x, rho, u, p, body = profiles(with_av)
    waves = EXACT.wave_positions(t, X0)
    # away from the waves by 5 cells, where the smeared fronts do not reach
    left = (x > waves["left_tail"] + 5 * H) & (x < waves["contact"] - 5 * H)
    right = (x > waves["contact"] + 5 * H) & (x < waves["right_head"] - 5 * H)
    assert np.median(p[left | right]) == pytest.approx(EXACT.p_star, rel=0.05)
    assert np.median(u[left | right]) == pytest.approx(EXACT.u_star, rel=0.05)
    assert np.median(rho[left]) == pytest.approx(EXACT.rho_star_left, rel=0.05)
    assert np.median(rho[right]) == pytest.approx(EXACT.rho_star_right, rel=0.05)


def test_shock_and_contact_within_two_cells(with_av):
    t, x, rho, u, p, body = profiles(with_av)
    waves = EXACT.wave_positions(t, X0)
    # the contact is where the gas of the left body meets that of the right one
    contact = 0.5 * (x[body == 0].max() + x[body == 1].min())
    # the shock: the last particle whose pressure is above the mid-jump value
    shock = x[p > 0.5 * (EXACT.p_star + SOD_RIGHT.p)].max()
    assert abs(contact - waves["contact"]) < 2 * H
    assert abs(shock - waves["right_head"]) < 2 * H


def test_mass_and_energy_are_conserved(with_av):
    """A closed tube with slip ends: kinetic + internal energy stays what it was."""
    series = with_av.series()
    total = series["total_energy"]
    # e_L = 2.5 over length 0.5 at rho 1, e_R = 2 over 0.5 at rho 0.125: E0 = 1.375
    assert total[0] == pytest.approx(1.375, rel=1e-12)
    # the step's first-order energy error stays below 1% (measured 2e-5 at cfl 0.5)
    assert abs(total[-1] - total[0]) < 0.01 * total[0]


# -- the defaults (issue 51) ---------------------------------------------------------------

def defaults_scene(cfl, method=None):
    """The example with the method and the material's keys left out (but the model): what a
    user writes who names only the gas and its bodies; `method` what the scene gives of its own."""
    scene = sod_scene()
    scene["materials"]["air"] = {"model": "ideal_gas"}
    scene["method"] = dict(method or {})
    scene["time"]["cfl"] = cfl
    return scene


def defaults_l1(tmp_path, cfl, method=None):
    case = run_scene(defaults_scene(cfl, method), tmp_path / f"cfl{cfl}")
    t, x, rho, *_ = profiles(case)
    assert case.result.status == "complete"
    return float(np.mean(np.abs(rho - EXACT.sample(x, t, X0)[0])))


def test_a_gas_scene_that_names_no_shape_function_gets_the_cubic_splines():
    """The ideal gas's method default (IdealGas.method_defaults), resolved once as the scene is
    read; a shape function the scene names is kept (and so its results)."""
    from solver.scene_checks import load_scene
    assert load_scene(defaults_scene(0.5)).method.shape_function == "cubic_bspline"
    assert load_scene(defaults_scene(0.5, {"shape_function": "linear"})).method.shape_function == "linear"
    assert load_scene(defaults_scene(0.5, {"transfer": "pic"})).method.model_dump()["shape_function"] == "cubic_bspline"


# The bound: the 0.0146 of test_l1_density_error_with_artificial_viscosity (a first-order
# scheme's smeared shock and plateaus and rarefaction within 5 %), inside the 0.015.
# Measured 0.0034 at cfl 0.5 (docs/benchmarks.md "Sod"); linear hats 0.0115.
def test_the_defaults_meet_the_l1_bound_at_cfl_one_half(tmp_path):
    assert defaults_l1(tmp_path, 0.5) < 0.0146


@pytest.mark.slow
@pytest.mark.parametrize("cfl", [0.2, 0.1, 0.025])
def test_the_defaults_meet_the_l1_bound_at_smaller_steps(tmp_path, cfl):
    assert defaults_l1(tmp_path, cfl) < 0.0146


# Linear hats named, the rest the gas's defaults: the density from the grid keeps the particles'
# volumes with the room they take (solver/gas_density.py). Measured 0.0115, 0.0075 and 0.0068;
# with the particles' own volumes J V0 (`density_from_grid: false`) 0.039, 0.021 and 0.013.
@pytest.mark.parametrize("cfl", [0.5, pytest.param(0.2, marks=pytest.mark.slow),
                                 pytest.param(0.05, marks=pytest.mark.slow)])
def test_linear_hats_meet_the_l1_bound_with_the_density_from_the_grid(tmp_path, cfl):
    assert defaults_l1(tmp_path, cfl, {"shape_function": "linear"}) < 0.0146


def test_linear_hats_miss_the_bound_with_the_particles_own_volumes(tmp_path):
    """What the density from the grid mends: an expanded gas's volumes J V0 drift from the
    particles' spacing (the left plateau 54 % low), L1 0.039 at cfl 0.5."""
    scene = defaults_scene(0.5, {"shape_function": "linear"})
    scene["materials"]["air"]["density_from_grid"] = False
    t, x, rho, u, p, body = profiles(run_scene(scene, tmp_path / "own"))
    waves = EXACT.wave_positions(t, X0)
    left = (x > waves["left_tail"] + 5 * H) & (x < waves["contact"] - 5 * H)
    assert np.mean(np.abs(rho - EXACT.sample(x, t, X0)[0])) > 0.0146
    assert np.median(p[left]) < 0.8 * EXACT.p_star
