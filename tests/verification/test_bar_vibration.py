"""E1: axial vibration of an elastic bar (review 6.1.1), fixed at x = 0, free at x = L.

Exact solution for mode n: v(x, t) = v0 cos(w_n t) sin(b_n x), b_n = (2n - 1) pi / (2L),
w_n = b_n sqrt(E / rho); the centre-of-mass velocity is v0 / (b_n L) cos(w_n t).
1D here is uniaxial strain; with nu = 0 the modulus is E as in the reference.
"""
import math

import numpy as np
import pytest

from mpm_cases import centre_of_mass_velocity

L, E, RHO, V0 = 25.0, 100.0, 1.0, 0.1
C = math.sqrt(E / RHO)


def bar_scene(mode, cells, ppc, scheme="musl", transfer="flip", periods=2.0, frames=81):
    h = L / cells
    beta = (2 * mode - 1) * math.pi / (2 * L)
    omega = beta * C
    end = periods * 2 * math.pi / omega
    return {
        "version": 1, "name": f"bar-mode-{mode}", "dimension": 1,
        "method": {"scheme": scheme, "transfer": transfer, "flip_ratio": 1.0},
        "grid": {"lower": [0.0], "upper": [L + 4 * h], "cell_size": h},
        "materials": {"bar": {"model": "linear_elastic", "density": RHO, "youngs_modulus": E, "poisson_ratio": 0.0}},
        "bodies": [{"name": "bar", "material": "bar", "particles_per_cell": ppc,
                    "geometry": {"type": "box", "lower": [0.0], "upper": [L]},
                    "initial_velocity": [f"{V0} * sin({beta!r} * x)"]}],
        "boundary_conditions": [{"type": "velocity", "where": {"type": "box", "lower": [-1.0], "upper": [0.25 * h]},
                                 "velocity": [0.0]}],
        "time": {"end": end, "dt": 0.1 * h / C},
        "output": {"frames": frames, "fields": ["velocity"]},
    }, beta, omega


def vcm_error(case, beta, omega):
    """max over frames of |v_cm - exact| relative to the exact amplitude."""
    amplitude = V0 / (beta * L)
    errors = []
    for frame in case.frames():
        exact = amplitude * math.cos(omega * frame["time"])
        errors.append(abs(centre_of_mass_velocity(frame)[0] - exact) / amplitude)
    return max(errors)


def final_amplitude(case, beta, omega):
    """v_cm amplitude over the last period, from the last frames, relative to the exact one."""
    frames = case.frames()
    amplitude = V0 / (beta * L)
    last_period = [f for f in frames if f["time"] >= frames[-1]["time"] - 2 * math.pi / omega]
    return max(abs(centre_of_mass_velocity(f)[0]) for f in last_period) / amplitude


@pytest.mark.parametrize("cells,ppc", [(13, 1), (16, 2)])   # the text's and the figure's set-ups (Part F, F8)
def test_mode1_musl_flip_tracks_exact_centre_of_mass_velocity(run_case, cells, ppc):
    scene, beta, omega = bar_scene(1, cells, ppc)
    case = run_case(scene)
    assert case.result.status == "complete"
    # the reference: FLIP/MUSL follows the exact v_cm, "a few percent" over two periods
    assert vcm_error(case, beta, omega) < 0.05


def test_mode1_error_decreases_with_refinement(run_case):
    errors = []
    for cells in (13, 26, 52):
        scene, beta, omega = bar_scene(1, cells, 1, periods=1.0)
        errors.append(vcm_error(run_case(scene, f"bar{cells}"), beta, omega))
    assert errors[0] > errors[1] > errors[2]


def test_mode1_pic_is_dissipative(run_case):
    flip_scene, beta, omega = bar_scene(1, 16, 2, transfer="flip")
    pic_scene, _, _ = bar_scene(1, 16, 2, transfer="pic")
    flip = final_amplitude(run_case(flip_scene, "flip"), beta, omega)
    pic = final_amplitude(run_case(pic_scene, "pic"), beta, omega)
    assert flip > 0.97           # FLIP keeps the amplitude
    assert pic < 0.9 * flip      # PIC visibly loses it ("a big numerical dissipation")


def test_mode10_musl_conserves_energy_better_than_usl(run_case):
    drift = {}
    for scheme in ("usl", "musl"):
        scene, _, _ = bar_scene(10, 50, 1, scheme=scheme, periods=4.0, frames=5)
        series = run_case(scene, scheme).series()
        total = series["total_energy"]
        drift[scheme] = abs(total[-1] - total[0]) / total[0]
    assert drift["musl"] < drift["usl"]
