"""Shape-function and transfer identities (review 3.1, A.1; verification spec E23, E32).

Exact properties of the linear hat functions and of P2G, checked to round-off.
"""
import numpy as np
import pytest

from solver import kernels, shape
from solver.threads import ScatterCopies

ROUND_OFF = 1e-12
linear = shape.get("linear")


def no_copies(n_nodes: int, dim: int) -> tuple:
    """The P2G kernels' per-thread copies for one thread: none (they add into the grid)."""
    c = ScatterCopies(n_nodes, dim, 1)
    return c.mass, c.momentum, c.force


def make_grid(dim, cells=6, h=0.25, lower=-0.5):
    cells_a = np.full(dim, cells, dtype=np.int64)
    strides = np.concatenate(([1], np.cumprod(cells_a + 1)[:-1])).astype(np.int64)
    lower_a = np.full(dim, lower)
    h_a = np.full(dim, h)
    return lower_a, h_a, cells_a, strides


def node_positions(lower, h, cells):
    axes = [lower[a] + h[a] * np.arange(cells[a] + 1) for a in range(len(h))]
    mesh = np.meshgrid(*axes, indexing="ij")
    return np.stack([m.transpose().ravel() for m in mesh], axis=1)


def stencil(x, lower, h, cells, strides):
    n, dim = x.shape
    nk = linear.SUPPORT**dim
    idx = np.zeros((n, nk), np.int64)
    w = np.zeros((n, nk))
    dw = np.zeros((n, nk, dim))
    outside = linear.weights(kernels.stencil_spec(dim, nk), x, lower, 1.0 / h, cells, strides, idx, w, dw, 1)
    return outside, idx, w, dw


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_linear_partition_of_unity_and_linear_reproduction(dim):
    rng = np.random.default_rng(dim)
    lower, h, cells, strides = make_grid(dim)
    x = lower + rng.random((500, dim)) * h * cells
    outside, idx, w, dw = stencil(x, lower, h, cells, strides)
    assert outside == -1
    nodes = node_positions(lower, h, cells)
    assert np.all(w >= 0.0)
    np.testing.assert_allclose(w.sum(axis=1), 1.0, atol=ROUND_OFF)
    np.testing.assert_allclose(dw.sum(axis=1), 0.0, atol=ROUND_OFF / h[0])
    # sum_I phi_I x_I = x and sum_I x_I (x) grad phi_I = identity
    np.testing.assert_allclose(np.einsum("pk,pka->pa", w, nodes[idx]), x, atol=ROUND_OFF)
    gradient_of_x = np.einsum("pka,pkb->pab", nodes[idx], dw)
    np.testing.assert_allclose(gradient_of_x, np.broadcast_to(np.eye(dim), gradient_of_x.shape), atol=ROUND_OFF)


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_linear_gradient_matches_finite_differences(dim):
    rng = np.random.default_rng(10 + dim)
    lower, h, cells, strides = make_grid(dim)
    # keep points away from cell faces, where the hat gradient jumps
    cell = rng.integers(0, cells[0], size=(50, dim))
    x = lower + (cell + 0.2 + 0.6 * rng.random((50, dim))) * h
    _, idx, w, dw = stencil(x, lower, h, cells, strides)
    eps = 1e-6 * h[0]
    for d in range(dim):
        shift = np.zeros(dim)
        shift[d] = eps
        _, idx_p, w_p, _ = stencil(x + shift, lower, h, cells, strides)
        _, idx_m, w_m, _ = stencil(x - shift, lower, h, cells, strides)
        assert np.array_equal(idx_p, idx) and np.array_equal(idx_m, idx)
        np.testing.assert_allclose((w_p - w_m) / (2 * eps), dw[:, :, d], rtol=1e-6, atol=1e-6 / h[0])


def test_particle_outside_the_grid_is_reported():
    lower, h, cells, strides = make_grid(2)
    x = np.array([[0.0, 0.0], [0.1, 2.0], [0.2, 0.2]])
    outside, *_ = stencil(x, lower, h, cells, strides)
    assert outside == 1


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_p2g_conserves_mass_and_momentum(dim):
    rng = np.random.default_rng(20 + dim)
    lower, h, cells, strides = make_grid(dim)
    n = 300
    x = lower + (0.05 + 0.9 * rng.random((n, dim))) * h * cells
    mass = rng.random(n) + 0.5
    vel = rng.normal(size=(n, dim))
    volume = rng.random(n)
    stress = rng.normal(size=(n, 3, 3))
    acc = np.zeros((1, dim))
    _, idx, w, dw = stencil(x, lower, h, cells, strides)
    n_nodes = int(np.prod(cells + 1))
    gm, gp, gf = np.zeros(n_nodes), np.zeros((n_nodes, dim)), np.zeros((n_nodes, dim))
    kernels.p2g(kernels.stencil_spec(dim, w.shape[1]), idx, w, dw, mass, vel, volume, stress, acc, gm, gp, gf,
                *no_copies(n_nodes, dim))
    assert gm.sum() == pytest.approx(mass.sum(), rel=ROUND_OFF)
    np.testing.assert_allclose(gp.sum(axis=0), (mass[:, None] * vel).sum(axis=0), rtol=ROUND_OFF, atol=ROUND_OFF * n)
    # internal forces are equal and opposite inside the body: they sum to zero
    np.testing.assert_allclose(gf.sum(axis=0), 0.0, atol=ROUND_OFF * np.abs(gf).max())


def test_cell_crossing_internal_force_jump():
    """E23: 1D, uniform stress sigma and volume V, hat functions. With 2 particles on each
    side of a node its internal force is 0; move one across and it becomes 2 V sigma / h."""
    lower, h, cells, strides = make_grid(1, cells=2, h=1.0, lower=0.0)
    sigma, V = 3.0, 0.5

    def force_on_middle_node(x):
        x = np.asarray(x, dtype=float).reshape(-1, 1)
        n = x.shape[0]
        stress = np.zeros((n, 3, 3))
        stress[:, 0, 0] = sigma
        _, idx, w, dw = stencil(x, lower, h, cells, strides)
        gm, gp, gf = np.zeros(3), np.zeros((3, 1)), np.zeros((3, 1))
        kernels.p2g(kernels.stencil_spec(1, 2), idx, w, dw, np.ones(n), np.zeros((n, 1)), np.full(n, V), stress,
                    np.zeros((1, 1)), gm, gp, gf, *no_copies(3, 1))
        return gf[1, 0]

    assert force_on_middle_node([0.25, 0.75, 1.25, 1.75]) == pytest.approx(0.0, abs=1e-15)
    # one particle of the left cell has crossed into the right one: 1 on the left, 3 on the right
    assert force_on_middle_node([0.25, 1.05, 1.25, 1.75]) == pytest.approx(2 * V * sigma / h[0], rel=1e-14)


def test_small_nodal_mass_cut_off():
    """Review eq. 2.63 / E24: a node below the mass cut-off gets no acceleration, while
    its velocity (a mass-weighted average) is kept, so rigid motion stays exact."""
    gm = np.array([1.0, 1e-14])
    mom = np.array([[2.0], [3e-14]])
    force = np.array([[1.0], [1.0]])
    v_new = np.empty((2, 1))
    kernels.integrate_nodes(kernels.axes(1), 0.1, gm, mom, force, 1e-9, v_new)
    assert force[:, 0] == pytest.approx([2.0, 3.0])   # v_I^t, in the force's array
    assert v_new[:, 0] == pytest.approx([2.1, 3.0])
