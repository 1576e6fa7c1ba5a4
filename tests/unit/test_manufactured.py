"""The manufactured-solution scenes: their body forces balance the exact motion, and the
example files are what the builders make."""
import json

import numpy as np
import pytest

from solver.examples import DEFAULT_DIR
from solver.expressions import compile_expression
from solver.manufactured import (
    NU, PERIOD, RHO, VORTEX_E, VORTEX_RHO, E, cube_displacement, cube_scene, example_scenes, lame, vortex_displacement,
    vortex_scene,
)

STEP = 1e-4   # finite-difference step: truncation ~ STEP^2 ~ 1e-8 relative, round-off ~ 1e-16 / STEP^2 ~ 1e-8


def piola(F, lam, mu):
    """Neo-Hookean P = mu (F - F^-T) + lambda ln J F^-T (review B.6), 2x2 plane strain."""
    Finv_T = np.linalg.inv(F).transpose(0, 2, 1)
    lnJ = np.log(np.linalg.det(F))
    return mu * (F - Finv_T) + lam * lnJ[:, None, None] * Finv_T


def deformation_gradient(motion, X, t):
    F = np.empty((len(X), 2, 2))
    for b in range(2):
        dX = np.zeros(2)
        dX[b] = STEP
        F[:, :, b] = (motion(X + dX, t) - motion(X - dX, t)) / (2 * STEP)
    return F


def balance_force(motion, X, t, lam, mu, rho, period):
    """b = x_tt - Div_X P / rho, both by central differences of the exact motion
    (time step STEP * period, so the truncation error is relative to the motion's period)."""
    dt = STEP * period
    accel = (motion(X, t + dt) - 2 * motion(X, t) + motion(X, t - dt)) / dt**2
    div = np.zeros((len(X), 2))
    for b in range(2):
        dX = np.zeros(2)
        dX[b] = STEP
        P_plus = piola(deformation_gradient(motion, X + dX, t), lam, mu)
        P_minus = piola(deformation_gradient(motion, X - dX, t), lam, mu)
        div += (P_plus[:, :, b] - P_minus[:, :, b]) / (2 * STEP)
    return accel - div / rho


def scene_force(scene, X, t):
    env = {"X": X[:, 0], "Y": X[:, 1], "x": X[:, 0], "y": X[:, 1], "t": t}
    return np.stack([compile_expression(e, ("x", "y", "X", "Y", "t")).evaluate(**env) for e in scene["body_force"]],
                    axis=1)


@pytest.mark.parametrize("t", [0.13, 0.5, 0.81])
def test_vortex_force_balances_the_motion(t):
    """The corrected b_Theta (F1); with the printed sign the check fails wherever g'(t) != 0."""
    rng = np.random.default_rng(1)
    R, theta = rng.uniform(0.8, 1.2, 20), rng.uniform(0, 2 * np.pi, 20)
    X = np.stack([R * np.cos(theta), R * np.sin(theta)], axis=1)
    expected = balance_force(lambda X, t: X + vortex_displacement(X, t), X, t, *lame(VORTEX_E, NU), VORTEX_RHO, 2.0)
    got = scene_force(vortex_scene(0.1), X, t)
    # finite-difference error ~1e-6 of the force scale, far below the O(1) of a wrong sign
    assert np.allclose(got, expected, rtol=1e-4, atol=1e-5 * np.abs(expected).max())


@pytest.mark.parametrize("t", [0.003, 0.0121])
def test_square_force_balances_the_motion(t):
    rng = np.random.default_rng(2)
    X = rng.uniform(0.05, 0.95, (20, 2))
    expected = balance_force(lambda X, t: X + cube_displacement(X, t, 0.05), X, t, *lame(E, NU), RHO, PERIOD)
    got = scene_force(cube_scene(2, 0.1, 0.05), X, t)
    assert np.allclose(got, expected, rtol=1e-4, atol=1e-5 * np.abs(expected).max())


@pytest.mark.parametrize("name", sorted(example_scenes()))
def test_example_files_are_the_builders_scenes(name):
    assert json.loads((DEFAULT_DIR / f"{name}.json").read_text()) == example_scenes()[name]


def test_vortex_starts_with_the_exact_velocity():
    rng = np.random.default_rng(3)
    R, theta = rng.uniform(0.75, 1.25, 20), rng.uniform(0, 2 * np.pi, 20)
    X = np.stack([R * np.cos(theta), R * np.sin(theta)], axis=1)
    dt = 1e-6
    exact = (vortex_displacement(X, dt) - vortex_displacement(X, -dt)) / (2 * dt)
    got = np.stack([compile_expression(e, ("x", "y")).evaluate(x=X[:, 0], y=X[:, 1])
                    for e in vortex_scene(0.1)["bodies"][0]["initial_velocity"]], axis=1)
    assert np.allclose(got, exact, rtol=1e-6, atol=1e-9)
