"""E23: the cell-crossing force jump (review 3.2, Fig. 12) and how smooth shape
functions remove it.

1D, h = 1, uniform stress sigma and volume V on every particle, 2 particles per
cell. The internal force on node I is f_I = -V sigma sum_p N_I'(x_p). One
particle moves across node 4 (a cell face) from 4 - delta to 4 + delta; only its
own term changes, by -V sigma [N_I'(4 + delta) - N_I'(4 - delta)].

- Linear hats: N' jumps from 1/h to -1/h at the node, so f_4 jumps by exactly
  2 V sigma / h however small delta is (the derived value of VERIFICATION_CASES
  E23). Quadratic Bernstein functions jump the same way at element ends (their
  end-node function (1 - |r|)^2, r in element sizes 2h, has slope -+1/h at the
  end), which is why they are kept to TLMPM.
- C1 functions (uGIMP, quadratic and cubic B-splines): the change is bounded by
  V sigma 2 delta max|N''|, with max|N''| = 2/h^2 for the quadratic and cubic
  B-splines and 2/(h l_p) = 4/h^2 for uGIMP with l_p = h/2: O(delta/h) of the
  linear jump, and it vanishes with delta.
"""
from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from solver import kernels, shape
from solver.state import Grid, make_stencil
from solver.threads import ScatterCopies

H, V, SIGMA, CELLS = 1.0, 0.5, 3.0, 8
MAX_SECOND_DERIVATIVE = {"gimp": 4.0 / H**2, "quadratic_bspline": 2.0 / H**2, "cubic_bspline": 2.0 / H**2}


def no_copies(n_nodes: int, dim: int) -> tuple:
    """The P2G kernels' per-thread copies for one thread: none (they add into the grid)."""
    c = ScatterCopies(n_nodes, dim, 1)
    return c.mass, c.momentum, c.force


def grid_1d() -> Grid:
    nodes = CELLS + 1
    return Grid(lower=np.zeros(1), h=np.array([H]), cells=np.array([CELLS]), mass=np.zeros(nodes),
                momentum=np.zeros((nodes, 1)), force=np.zeros((nodes, 1)), v_old=np.zeros((nodes, 1)),
                v_new=np.zeros((nodes, 1)))


def internal_forces(name: str, x: np.ndarray) -> np.ndarray:
    grid = grid_1d()
    module = shape.get(name)
    n = x.shape[0]
    particles = SimpleNamespace(extra={"domain_length": np.full((n, 1), H / 2)}, F=np.ones((n, 1, 1)))
    stencil = make_stencil(n, 1, module.SUPPORT)
    spec = kernels.stencil_spec(1, module.SUPPORT)
    assert shape.evaluate(module, spec, x, particles, grid, stencil) == -1
    stress = np.zeros((n, 3, 3))
    stress[:, 0, 0] = SIGMA
    kernels.p2g(spec, stencil.idx, stencil.w, stencil.dw, np.ones(n), np.zeros((n, 1)), np.full(n, V), stress,
                np.zeros((1, 1)), grid.mass, grid.momentum, grid.force, *no_copies(grid.n_nodes, 1))
    return grid.force[:, 0]


def particles_with_one_at(position: float) -> np.ndarray:
    """2 per cell in cells 1..6, the one at 3.75 moved to `position`."""
    x = (np.arange(1, 7)[:, None] + np.array([0.25, 0.75])).ravel()
    x[x == 3.75] = position
    return np.ascontiguousarray(x[:, None])


def force_change_across_node_4(name: str, delta: float) -> np.ndarray:
    return internal_forces(name, particles_with_one_at(4 + delta)) - internal_forces(name, particles_with_one_at(4 - delta))


def test_uniform_stress_gives_no_force_inside_the_body():
    """Before anything moves, interior nodes (2..5, away from the body's ends) feel no force."""
    x = particles_with_one_at(3.75)
    for name in ["linear", *MAX_SECOND_DERIVATIVE]:
        np.testing.assert_allclose(internal_forces(name, x)[3:6], 0.0, atol=1e-13)


@pytest.mark.parametrize("delta", [1e-1, 1e-3, 1e-6])
def test_c0_functions_jump_by_two_v_sigma_over_h(delta):
    assert force_change_across_node_4("linear", delta)[4] == pytest.approx(2 * V * SIGMA / H, rel=1e-12)
    # Bernstein, element [2h, 4h] then [4h, 6h], t = 1 - delta/2h then delta/2h: the end node's
    # slope goes from t/h to -(1 - t)/h, a change of 2 (1 - delta/2h)/h, which tends to the hats' 2/h
    expected = 2 * V * SIGMA / H * (1 - delta / (2 * H))
    assert force_change_across_node_4("bernstein", delta)[4] == pytest.approx(expected, rel=1e-9)


@pytest.mark.parametrize("name", list(MAX_SECOND_DERIVATIVE))
@pytest.mark.parametrize("delta", [1e-1, 1e-3, 1e-6])
def test_c1_functions_change_by_order_delta(name, delta):
    change = np.abs(force_change_across_node_4(name, delta))
    bound = V * SIGMA * 2 * delta * MAX_SECOND_DERIVATIVE[name]
    assert change.max() <= bound * (1 + 1e-9) + 1e-12
    assert change.max() < 0.5 * (2 * V * SIGMA / H)   # well below the linear jump even at delta = h/10
