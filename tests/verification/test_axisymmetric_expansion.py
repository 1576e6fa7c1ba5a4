"""Axisymmetric formulation on its own (review Appendix G): uniform radial expansion.

A thick tube (radii R_IN, B), between two slip walls (eps_zz = 0), has the initial
velocity v_r = A r and both its surfaces move with the material. The motion
r(t) = r0 (1 + A t) has no acceleration and a uniform stress, which satisfies the
radial equilibrium d sigma_rr / dr + (sigma_rr - sigma_thth) / r = 0 only because
sigma_rr = sigma_thth: the hoop force and the hoop rate of eq. G.2 / G.4 must both be
right. With D_rr = D_thth = A / (1 + A t) the hypoelastic stress is exactly
sigma_rr = sigma_thth = 2 (lambda + mu) ln(1 + A t), sigma_zz = 2 lambda ln(1 + A t).
A plane-strain run of the same scene (no hoop terms) is far from it.

The same in TLMPM (the hoop terms in the reference configuration, solver/axisymmetric.py):
F_thth = r / R = 1 + A t, P_thth = J sigma_thth / F_thth and the hoop force with N_I(X_p) / R_p.
There the surface nodes are material points: they move at the constant A R.
"""
import math

import numpy as np
import pytest

R_IN, B, HZ, CELL, PPC = 0.5, 1.0, 0.2, 0.05, 2
E, NU, RHO = 1000.0, 0.3, 1.0
LAM, MU = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
C = math.sqrt((LAM + 2 * MU) / RHO)
STRAIN = 0.01                          # A t at the end
END = 2 * (B - R_IN) / C               # one wave round trip
A = STRAIN / END


def expansion_scene(axisymmetric=True, formulation="ulmpm"):
    scene = {
        "name": "radial-expansion", "dimension": 2, "axisymmetric": axisymmetric,
        "grid": {"lower": [0.0, 0.0], "upper": [B + CELL, HZ], "cell_size": CELL},
        "materials": {"m": {"model": "linear_elastic", "density": RHO, "youngs_modulus": E, "poisson_ratio": NU}},
        "bodies": [{"name": "cylinder", "material": "m", "particles_per_cell": PPC,
                    "geometry": {"type": "box", "lower": [R_IN, 0.0], "upper": [B, HZ]},
                    "initial_velocity": [f"{A!r} * x", 0.0]}],
        "boundary_conditions": [
            {"type": "wall", "face": "y-", "mode": "slip"}, {"type": "wall", "face": "y+", "mode": "slip"},
            # the surface nodes move with the material passing them: v = A r / (1 + A t)
            *({"type": "velocity", "where": {"type": "box", "lower": [r - 0.1 * CELL, -1.0], "upper": [r + 0.1 * CELL, 1.0]},
               "velocity": [f"{A * r!r} / (1 + {A!r} * t)", None]} for r in (R_IN, B)),
        ],
        "time": {"end": END, "cfl": 0.5},
        "output": {"frames": 2, "fields": ["position", "stress"]},
    }
    if formulation == "tlmpm":   # the nodes are those of the reference grid: the surface's at R move at A R
        scene["method"] = {"formulation": "tlmpm"}
        for condition, r in zip(scene["boundary_conditions"][2:], (R_IN, B)):
            condition["velocity"] = [A * r, None]
    return scene


def stresses(case):
    f0, f1 = case.frame(0)["fields"], case.frame(-1)["fields"]
    o0, o1 = np.argsort(f0["id"]), np.argsort(f1["id"])
    return f0["position"][o0], f1["position"][o1], f1["stress"][o1]


def test_uniform_expansion_is_exact(run_case):
    case = run_case(expansion_scene(), "axisymmetric")
    x0, x1, stress = stresses(case)
    log = math.log(1 + STRAIN)
    exact_rr, exact_zz = 2 * (LAM + MU) * log, 2 * LAM * log
    # Uniform stress and a linear velocity are reproduced exactly by linear shape functions
    # with the hoop terms but for one effect: masses grow with r (2 pi r weighting), so the
    # nodal velocity of v = A r, a mass-weighted average, is A r_I (1 + 3/16 (h / r_I)^2) with
    # two particles per cell (worked out by hand for particles at r_I +- h/4, +- 3h/4). With
    # r >= R_IN = 10 h that is <= 0.19 % in L; the imbalance it makes travels and reflects as
    # a wave of the same order, adding to it along its path (a few times 0.19 %). Allow 1 %.
    assert np.allclose(stress[:, 0], exact_rr, rtol=0.01)          # sigma_rr
    assert np.allclose(stress[:, 2], exact_rr, rtol=0.01)          # sigma_thth (Voigt zz)
    assert np.allclose(stress[:, 1], exact_zz, rtol=0.01)          # sigma_zz (Voigt yy)
    assert np.allclose(stress[:, 3:], 0.0, atol=0.01 * exact_rr)   # no shear
    # the particles follow r = r0 (1 + A t): 1 % of the radial displacement
    assert np.allclose(x1[:, 0], x0[:, 0] * (1 + STRAIN), rtol=0.01 * STRAIN)


def test_plane_strain_is_not_the_axisymmetric_solution(run_case):
    case = run_case(expansion_scene(axisymmetric=False), "plane")
    _, _, stress = stresses(case)
    exact_rr = 2 * (LAM + MU) * math.log(1 + STRAIN)
    # without the hoop rate sigma_zz (the out-of-plane stress) is lambda eps only: ~ half of it
    assert np.abs(stress[:, 2] / exact_rr - 1).mean() > 0.3


def test_uniform_expansion_is_exact_in_tlmpm(run_case):
    case = run_case(expansion_scene(formulation="tlmpm"), "axisymmetric-tlmpm")
    x0, x1, stress = stresses(case)
    log = math.log(1 + STRAIN)
    exact_rr, exact_zz = 2 * (LAM + MU) * log, 2 * LAM * log
    # The reference grid's nodes are material points and the surface ones are prescribed
    # exactly, so no imbalance travels and reflects as in ULMPM: what remains is the 2 pi R
    # weighting of the nodal velocity, <= 0.19 % in L (above). Measured: 0.04 % at most. The
    # bound of 0.2 % tells the hoop force's measure: with V_p sigma_thth in place of
    # V0_p P_thth (1 % apart at this strain: P_thth = J sigma_thth / F_thth) the stresses are
    # 0.4 % off; without the hoop force 40 %.
    assert np.allclose(stress[:, 0], exact_rr, rtol=0.002)          # sigma_rr
    assert np.allclose(stress[:, 2], exact_rr, rtol=0.002)          # sigma_thth: the hoop rate and F_thth = r / R
    assert np.allclose(stress[:, 1], exact_zz, rtol=0.002)          # sigma_zz
    assert np.allclose(stress[:, 3:], 0.0, atol=0.002 * exact_rr)
    assert np.allclose(x1[:, 0], x0[:, 0] * (1 + STRAIN), rtol=0.002 * STRAIN)
