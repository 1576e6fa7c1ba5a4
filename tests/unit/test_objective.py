"""The plastic models' trial-stress helpers (solver/materials/kernels/objective.py), on nine
scalars, against the same tensor algebra written with numpy 3x3 matrices."""
from __future__ import annotations

import numpy as np
import pytest

from solver.materials.kernels import objective

RNG = np.random.default_rng(7)
ROUND_OFF = 1e-14   # a few operations of float64 round-off, relative to the magnitude


def _nine(matrix: np.ndarray) -> tuple:
    return tuple(float(v) for v in matrix.reshape(9))


def _padded(L: np.ndarray) -> np.ndarray:
    out = np.zeros((3, 3))
    out[:L.shape[0], :L.shape[1]] = L
    return out


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_rate_parts_are_sym_and_skew_of_the_padded_gradient(dim):
    L = RNG.normal(size=(dim, dim))
    D, w21, w02, w10 = objective.rate_parts(L)
    full = _padded(L)
    assert np.array_equal(np.array(D).reshape(3, 3), 0.5 * (full + full.T))
    W = 0.5 * (full - full.T)
    assert (w21, w02, w10) == (W[2, 1], W[0, 2], W[1, 0])


def test_rotated_is_the_hughes_winget_rotation():
    sigma = RNG.normal(size=(3, 3))
    sigma = sigma + sigma.T
    L = RNG.normal(size=(3, 3))
    dt = 0.3
    _, w21, w02, w10 = objective.rate_parts(L)
    W = 0.5 * (L - L.T)
    Q = np.linalg.solve(np.eye(3) - 0.5 * dt * W, np.eye(3) + 0.5 * dt * W)
    expected = Q @ sigma @ Q.T
    got = np.array(objective.rotated(sigma, w21, w02, w10, dt)).reshape(3, 3)
    assert np.max(np.abs(got - expected)) <= ROUND_OFF * np.max(np.abs(sigma))
    # a rotation: the invariants stay
    assert np.linalg.eigvalsh(0.5 * (got + got.T)) == pytest.approx(np.linalg.eigvalsh(sigma), rel=ROUND_OFF,
                                                                    abs=ROUND_OFF * np.max(np.abs(sigma)))


def test_rotated_without_spin_returns_the_stress_unchanged():
    sigma = RNG.normal(size=(3, 3))
    assert objective.rotated(sigma, 0.0, 0.0, 0.0, 0.1) == _nine(sigma)


def test_trial_deviator_pressure_von_mises_and_store():
    sigma = RNG.normal(size=(3, 3))
    sigma = sigma + sigma.T
    L = RNG.normal(size=(3, 3))
    D = 0.5 * (L + L.T)
    two_g_dt, K, dt = 0.7, 2.0, 0.1
    s = objective.trial_deviator(_nine(sigma), _nine(D), two_g_dt)
    dev = lambda a: a - np.trace(a) / 3.0 * np.eye(3)   # noqa: E731
    expected = dev(sigma) + two_g_dt * dev(D)
    assert np.max(np.abs(np.array(s).reshape(3, 3) - expected)) <= ROUND_OFF * np.max(np.abs(sigma))
    pressure = objective.mean_pressure(_nine(sigma)) - K * objective.trace(_nine(D)) * dt
    assert pressure == pytest.approx(-np.trace(sigma) / 3.0 - K * np.trace(D) * dt, rel=ROUND_OFF)
    assert objective.von_mises_of(s) == pytest.approx(np.sqrt(1.5 * np.sum(expected * expected)), rel=ROUND_OFF)
    assert objective.scaled(s, 2.0) == tuple(2.0 * v for v in s)
    out = np.empty((3, 3))
    objective.assemble_from(s, pressure, out)
    assert np.array_equal(out, np.array(s).reshape(3, 3) - pressure * np.eye(3))
