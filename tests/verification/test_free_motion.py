"""Rigid translation and free fall: exact kinematics, no spurious stress."""
import numpy as np
import pytest

E, NU, RHO = 1.0e4, 0.3, 1000.0


def block_scene(dim, velocity, gravity, scheme="musl", end=0.5, dt=1e-3):
    lower, upper = [-1.0] * dim, [1.0] * dim
    return {
        "version": 1, "name": "block", "dimension": dim,
        "method": {"scheme": scheme, "transfer": "flip", "flip_ratio": 1.0},
        "grid": {"lower": lower, "upper": upper, "cell_size": 0.1},
        "materials": {"m": {"model": "linear_elastic", "density": RHO, "youngs_modulus": E, "poisson_ratio": NU}},
        "bodies": [{"name": "b", "material": "m", "particles_per_cell": 2,
                    "geometry": {"type": "box", "lower": [-0.3] * dim, "upper": [0.2] * dim},
                    "initial_velocity": velocity}],
        "gravity": gravity,
        "time": {"end": end, "dt": dt},
        "output": {"frames": 6, "fields": ["position", "velocity", "stress"]},
    }


def stress_scale(speed):
    """rho c v: the stress an impact at this speed would make; spurious stress must be round-off of it."""
    lam = E * NU / ((1 + NU) * (1 - 2 * NU))
    mu = E / (2 * (1 + NU))
    return RHO * np.sqrt((lam + 2 * mu) / RHO) * speed


@pytest.mark.parametrize("scheme", ["musl", "usl", "usf"])
@pytest.mark.parametrize("dim", [1, 2, 3])
def test_rigid_translation_is_exact(run_case, dim, scheme):
    velocity = [0.4, -0.3, 0.2][:dim]
    case = run_case(block_scene(dim, velocity, [0.0] * dim, scheme=scheme, end=0.3))
    assert case.result.status == "complete"
    first, last = case.frame(0), case.frame(-1)
    order0, order1 = np.argsort(first["fields"]["id"]), np.argsort(last["fields"]["id"])
    moved = last["fields"]["position"][order1] - first["fields"]["position"][order0]
    np.testing.assert_allclose(moved, np.broadcast_to(np.array(velocity) * last["time"], moved.shape), atol=1e-12)
    np.testing.assert_allclose(last["fields"]["velocity"], np.broadcast_to(velocity, moved.shape), atol=1e-12)
    assert np.abs(last["fields"]["stress"]).max() <= 1e-9 * stress_scale(np.linalg.norm(velocity))


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_free_fall_under_gravity(run_case, dim):
    g = np.array([0.0, 0.0, -9.81][-dim:]) if dim > 1 else np.array([-9.81])
    dt, end = 1e-3, 0.3
    case = run_case(block_scene(dim, [0.0] * dim, g.tolist(), end=end, dt=dt))
    assert case.result.status == "complete"
    first, last = case.frame(0), case.frame(-1)
    t = last["time"]
    assert t == pytest.approx(end, abs=1e-12)
    order0, order1 = np.argsort(first["fields"]["id"]), np.argsort(last["fields"]["id"])
    u = last["fields"]["position"][order1] - first["fields"]["position"][order0]
    # symplectic Euler: u = g t^2/2 + g t dt/2, so the error of g t^2/2 is first order in dt
    exact = g * t**2 / 2
    discretisation = np.abs(g) * t * dt / 2
    assert np.all(np.abs(u - exact) <= discretisation * (1 + 1e-9) + 1e-12)
    np.testing.assert_allclose(last["fields"]["velocity"], np.broadcast_to(g * t, u.shape), rtol=1e-9, atol=1e-12)
    assert np.abs(last["fields"]["stress"]).max() <= 1e-9 * stress_scale(np.linalg.norm(g) * t)
