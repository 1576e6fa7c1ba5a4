"""The work of plastic flow (`plastic_work`, solver/materials/plastic_work.py) against closed forms,
and its place in the energy balance of an impact.

1. Simple shear of one material point of perfectly plastic material: the stress on the
   surface has q = q_y, so W_p = q_y eps_p V for every model, whatever the step.
2. The 2D copper bar hitting a wall (examples/copper_bar_impact_2d.json, Johnson-Cook): without
   the term, the energy error is the dissipated energy (most of the initial kinetic energy);
   with it, the error is that of the scheme, no larger than for the same bar made elastic.
"""
import json
import math
from pathlib import Path

import numpy as np
import pytest
from material_point import MaterialPoint

from solver import run
from solver.results import read_series

ROOT = Path(__file__).resolve().parents[2]
U = 2.0 ** -52      # unit round-off
E, NU, RHO = 200e9, 0.3, 7800.0
G = E / (2 * (1 + NU))
SY, COHESION = 250e6, 1e8
ELASTIC = {"density": RHO, "youngs_modulus": E, "poisson_ratio": NU}
# perfectly plastic versions of the four models; q_y: the von Mises stress on their surface in shear
PERFECT = {
    "j2_plasticity": ({"model": "j2_plasticity", "yield_stress": SY}, SY),
    "johnson_cook": ({"model": "johnson_cook", "A": SY, "B": 0.0, "n": 1.0, "C": 0.0, "reference_strain_rate": 1.0,
                      "room_temperature": 298.0, "melt_temperature": 1356.0, "taylor_quinney": 0.0}, SY),
    # friction angle 0: the compression cone is sqrt(J2) = 2 c / sqrt(3), so q = 2 c
    "drucker_prager": ({"model": "drucker_prager", "fit": "compression", "friction_angle": 0.0,
                        "dilation_angle": 0.0, "cohesion": COHESION}, 2.0 * COHESION),
    # Tresca: in plane shear the principal stresses are (t, 0, -t) on t = c, q = sqrt(3) c
    "mohr_coulomb": ({"model": "mohr_coulomb", "friction_angle": 0.0, "dilation_angle": 0.0,
                      "cohesion": COHESION}, math.sqrt(3.0) * COHESION),
}


@pytest.mark.parametrize("name", list(PERFECT))
def test_plastic_work_of_perfect_plasticity_in_simple_shear_is_q_y_eps_p_v(name):
    config, q_y = PERFECT[name]
    # isochoric: the volume stays V0 = 1 exactly (rigid_volume keeps it from det(F)'s round-off)
    point = MaterialPoint({**ELASTIC, **config}, dim=3, rigid_volume=True)
    rate, dt, steps = 1e3, 1e-7, 400          # shear strain 0.04, about 20 x the yield strain
    L = np.zeros((3, 3))
    L[0, 1] = rate
    for _ in range(steps):
        point.step(L, dt)
    eps_p, work = point.state("plastic_strain"), point.state("plastic_work")
    assert eps_p > 0.01
    # W_p and eps_p are sums of the same steps' positive increments, each with a relative
    # error of a few u (q_{n+1} = q_y to round-off, one product); each sum adds at most
    # `steps` u: so |W_p - q_y eps_p V| <= (2 steps + 16) u q_y eps_p
    assert work == pytest.approx(q_y * eps_p * 1.0, rel=(2 * steps + 16) * U)


def impact(model: str, end: float, tmp_path: Path) -> dict:
    scene = json.loads((ROOT / "examples" / "copper_bar_impact_2d.json").read_text())
    scene["time"]["end"] = end
    scene["output"] = {"frames": 2, "fields": ["position"], "energies": 10}
    if model == "linear_elastic":    # the same bar and scheme, elastic: the scheme's own error level
        copper = scene["materials"]["ofhc_copper"]
        scene["materials"]["ofhc_copper"] = {"model": "linear_elastic", **{
            key: copper[key] for key in ("density", "youngs_modulus", "poisson_ratio")}}
        del scene["bodies"][0]["initial_temperature"]
    return read_series(run(scene, tmp_path / model).result_path)


def test_plastic_work_closes_the_energy_balance_of_an_impact(tmp_path):
    end = 1e-5     # a third of the example: 0.49 of the kinetic energy dissipated by then
    plastic, elastic = impact("johnson_cook", end, tmp_path), impact("linear_elastic", end, tmp_path)
    assert "plastic_work" not in elastic         # no plastic material, no term
    kinetic0 = plastic["kinetic_energy"][0]
    error, work = plastic["energy_error"], plastic["plastic_work"]
    np.testing.assert_allclose(plastic["energy_balance"], plastic["total_energy"] + work - plastic["boundary_work"]
                               - plastic["external_work"], rtol=1e-12, atol=1e-12 * kinetic0)
    assert np.all(np.diff(work) >= 0.0)        # an associated flow never gives energy back
    without = np.max(np.abs(error - work)) / kinetic0    # what the balance said before the term
    with_term = np.max(np.abs(error)) / kinetic0
    scheme = np.max(np.abs(elastic["energy_error"])) / elastic["kinetic_energy"][0]
    assert without > 0.4
    assert with_term <= scheme
