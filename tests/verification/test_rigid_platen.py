"""Rigid platen (review 4.2.4): the reaction force on a platen that slowly compresses an elastic block.

A plane-strain block W x H stands on a slip floor (y = 0); a rigid platen above it
moves down by delta(t), slipping along x (its velocity is [null, v(t)]). The block is
then in uniaxial stress in-plane with eps_xx free and eps_zz = 0, so the exact static
load per unit depth is F = E / (1 - nu^2) * W * delta / H.
"""
import math

import numpy as np
import pytest

from mpm_cases import run_scene

H_CELL, PPC = 0.01, 2
W, H = 0.1, 0.2                    # 10 x 20 cells
E, NU, RHO = 1e7, 0.3, 1000.0
DELTA = 0.2 * H_CELL               # below the particles' offset (h / 4): the platen keeps its nodes
C_BAR = math.sqrt(E / (1 - NU**2) / RHO)
PERIOD = 2 * H / C_BAR             # lowest axial mode between the floor and the platen
RAMP = 20 * PERIOD                 # v(t) = DELTA / RAMP (1 - cos 2 pi t / RAMP): smooth start and stop
HOLD = 4 * PERIOD


def platen_scene(end=RAMP + HOLD):
    v = f"-where(t < {RAMP!r}, {DELTA / RAMP!r} * (1 - cos(2*pi*t/{RAMP!r})), 0)"
    return {
        "name": "rigid-platen", "dimension": 2,
        "grid": {"lower": [0.0, 0.0], "upper": [0.15, 0.25], "cell_size": H_CELL},
        "materials": {"rubber": {"model": "linear_elastic", "density": RHO, "youngs_modulus": E, "poisson_ratio": NU},
                      "steel": {"model": "rigid", "density": 7800.0}},
        "bodies": [
            {"name": "block", "material": "rubber", "particles_per_cell": PPC,
             "geometry": {"type": "box", "lower": [0.0, 0.0], "upper": [W, H]}},
            {"name": "platen", "material": "steel", "particles_per_cell": PPC,
             "geometry": {"type": "box", "lower": [0.0, H], "upper": [0.14, H + 2 * H_CELL]},
             "velocity": [None, v]},
        ],
        "boundary_conditions": [{"type": "wall", "face": "y-", "mode": "slip"},
                                {"type": "wall", "face": "x-", "mode": "slip"}],
        "time": {"end": end, "cfl": 0.5},
        "output": {"frames": 5, "fields": ["position", "velocity", "stress"]},
    }


@pytest.fixture(scope="module")
def platen(tmp_path_factory):
    return run_scene(platen_scene(), tmp_path_factory.mktemp("platen"))


def test_platen_moves_as_prescribed(platen):
    assert platen.result.status == "complete", platen.result.message
    first, last = platen.frame(0)["fields"], platen.frame(-1)["fields"]
    rigid = first["body"] == 1
    order0, order1 = np.argsort(first["id"]), np.argsort(last["id"])
    moved = last["position"][order1] - first["position"][order0]
    # the integral of v(t) over the ramp is DELTA; time stepping integrates v exactly at the step
    # ends only, so allow a (dt / RAMP)^2-order quadrature error, far below 1e-3 DELTA
    assert np.allclose(moved[rigid[order0], 1], -DELTA, rtol=1e-3)
    assert np.allclose(moved[rigid[order0], 0], 0.0, atol=1e-15)


def test_reaction_is_the_static_elastic_load(platen):
    s = platen.series()
    hold = s["time"] > RAMP
    reaction = np.average(s["reaction_platen_y"][hold], weights=s["dt"][hold])
    exact = E / (1 - NU**2) * W * DELTA / H
    # Tolerance 1.5 %: uniform strain is reproduced exactly by linear shape functions, so the
    # error is (a) the hypoelastic model at strain eps = DELTA / H = 1 %: rate-form stress
    # and current-area effects are O(eps) = 1 % (nu eps / (1 - nu) = 0.4 % area, the rest smaller); (b) what is left of the axial oscillation
    # after averaging over HOLD = 4 periods (a smooth ramp 20 periods long leaves an amplitude
    # of order (PERIOD / RAMP)^2 = 0.25 %, and averaging divides it further).
    assert reaction == pytest.approx(exact, rel=0.015)
    assert abs(np.average(s["reaction_platen_x"][hold], weights=s["dt"][hold])) < 1e-9 * exact
