"""E32: the property suite of every shape function (VERIFICATION_CASES Part B).

At random points of a small grid, including the cells at the grid ends, each
function must give: a partition of unity, sum_I grad phi_I = 0, linear
reproduction sum_I phi_I x_I = x and sum_I x_I (x) grad phi_I = identity,
gradients equal to central finite differences of the weights, non-negative
weights, and (cubic B-splines) interpolation at the grid ends.

Tolerances: the identities are exact in exact arithmetic, so they hold to a few
ulps of the O(1) sums; 1e-12 leaves a factor ~100 of round-off. The finite
difference with step eps = 1e-6 h has truncation error ~ eps^2 |phi'''| ~ 1e-12 / h^2
and cancellation error ~ 1e-16 / eps = 1e-10 / h; 1e-6 / h bounds both with margin
(at a kink of C0 functions the difference would be O(1/h): points within eps of a
cell face are avoided for them).
"""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from solver import kernels, shape
from solver.state import Grid, make_stencil

ALL = ["linear", "gimp", "cpgimp", "quadratic_bspline", "cubic_bspline", "bernstein"]
# distance a particle keeps from the grid ends, in cells: quadratic B-splines
# need h/2 (no node beyond the grid), a GIMP box of side h/2 needs h/4.
MARGIN = {"quadratic_bspline": 0.5, "gimp": 0.25, "cpgimp": 0.25}
C0_AT_FACES = {"linear": 1.0, "bernstein": 2.0}   # gradient kinks every this many cells


def make_grid(dim: int, cells: int = 6, h: float = 0.25) -> Grid:
    n = np.full(dim, cells, dtype=np.int64)
    nodes = int(np.prod(n + 1))
    lower = np.linspace(-0.3, 0.2, dim)
    return Grid(lower=lower, h=np.full(dim, h) * (1 + 0.1 * np.arange(dim)), cells=n,
                mass=np.zeros(nodes), momentum=np.zeros((nodes, dim)), force=np.zeros((nodes, dim)),
                v_old=np.zeros((nodes, dim)), v_new=np.zeros((nodes, dim)))


def particles_at(x: np.ndarray, grid: Grid, F: np.ndarray | None = None) -> SimpleNamespace:
    """What the GIMP functions read: box sides h/2 (2 particles per cell) and F."""
    n, dim = x.shape
    if F is None:
        F = np.repeat(np.eye(dim)[None], n, axis=0)
    return SimpleNamespace(x=x, F=F, extra={"domain_length": np.repeat(grid.h[None] / 2, n, axis=0)}, count=n)


def random_points(name: str, grid: Grid, n: int, rng) -> np.ndarray:
    margin = MARGIN.get(name, 0.0)
    s = rng.uniform(margin, grid.cells - margin, size=(n, len(grid.h)))
    # keep clear of the kinks of C0 functions so finite differences are meaningful
    period = C0_AT_FACES.get(name)
    if period:
        phase = np.mod(s, period)
        s = np.where(np.minimum(phase, period - phase) < 1e-4, s + 2e-4, s)
    # and always include the grid ends themselves (and the margin line)
    s[0] = margin
    s[1] = grid.cells - margin
    return grid.lower + s * grid.h


def evaluate(name: str, x: np.ndarray, grid: Grid, F=None):
    module = shape.get(name)
    dim = x.shape[1]
    stencil = make_stencil(x.shape[0], dim, module.SUPPORT)
    spec = kernels.stencil_spec(dim, module.SUPPORT**dim)
    outside = shape.evaluate(module, spec, np.ascontiguousarray(x), particles_at(x, grid, F), grid, stencil)
    return outside, stencil


@pytest.mark.parametrize("dim", [1, 2, 3])
@pytest.mark.parametrize("name", ALL)
def test_partition_of_unity_linear_reproduction_and_gradients(name, dim):
    rng = np.random.default_rng(5 + dim)
    grid = make_grid(dim)
    x = random_points(name, grid, 200, rng)
    outside, s = evaluate(name, x, grid)
    assert outside == -1
    nodes = grid.node_positions()[s.idx]                                   # (n, nk, dim)
    assert np.all((s.idx >= 0) & (s.idx < grid.n_nodes))
    np.testing.assert_allclose(s.w.sum(axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(s.dw.sum(axis=1), 0.0, atol=1e-12 * np.max(grid.inv_h))
    np.testing.assert_allclose(np.einsum("pk,pka->pa", s.w, nodes), x, atol=1e-12)
    np.testing.assert_allclose(np.einsum("pka,pkb->pab", nodes, s.dw),
                               np.broadcast_to(np.eye(dim), (len(x), dim, dim)), atol=1e-12)
    assert np.all(s.w >= -1e-15), "all these families are non-negative"


@pytest.mark.parametrize("dim", [1, 2])
@pytest.mark.parametrize("name", ALL)
def test_gradient_matches_finite_differences(name, dim):
    rng = np.random.default_rng(11)
    grid = make_grid(dim)
    h = float(np.min(grid.h))
    x = random_points(name, grid, 100, rng)
    margin = MARGIN.get(name, 0.0) + 1e-5
    x = np.clip(x, grid.lower + margin * grid.h, grid.lower + (grid.cells - margin) * grid.h)
    _, s = evaluate(name, x, grid)
    eps = 1e-6 * h
    for a in range(dim):
        plus, minus = x.copy(), x.copy()
        plus[:, a] += eps
        minus[:, a] -= eps
        # weights as dense per-node arrays: the stencils at x +- eps may start at other nodes
        dense = []
        for xs in (plus, minus):
            _, t = evaluate(name, xs, grid)
            full = np.zeros((len(x), grid.n_nodes))
            np.add.at(full, (np.arange(len(x))[:, None], t.idx), t.w)
            dense.append(full)
        fd = (dense[0] - dense[1]) / (2 * eps)
        analytic = np.zeros_like(fd)
        np.add.at(analytic, (np.arange(len(x))[:, None], s.idx), s.dw[:, :, a])
        np.testing.assert_allclose(analytic, fd, atol=1e-6 / h)


def test_cubic_bspline_interpolates_at_grid_ends():
    """Only the end node's (type 1) function is non-zero on a grid end, and it is 1
    there: boundary values are imposed exactly (review 3.4)."""
    grid = make_grid(1, cells=5)
    x = np.array([[grid.lower[0]], [grid.lower[0] + 5 * grid.h[0]]])
    _, s = evaluate("cubic_bspline", x, grid)
    for p, end in ((0, 0), (1, 5)):
        weights = dict(zip(s.idx[p], s.w[p]))
        assert weights[end] == pytest.approx(1.0, abs=1e-15)
        assert sum(abs(v) for k, v in weights.items() if k != end) < 1e-15


@pytest.mark.parametrize("cells", [3, 5, 8])
def test_cubic_bspline_boundary_types_on_small_grids(cells):
    """VERIFICATION_CASES B.3 check: PU and linear reproduction on 3, 5 and 8 cells,
    densely sampled (every type pairing, including both modified ends)."""
    grid = make_grid(1, cells=cells)
    x = grid.lower + np.linspace(0, cells, 2001)[:, None] * grid.h
    _, s = evaluate("cubic_bspline", x, grid)
    nodes = grid.node_positions()[s.idx][:, :, 0]
    np.testing.assert_allclose(s.w.sum(axis=1), 1.0, atol=1e-13)
    np.testing.assert_allclose((s.w * nodes).sum(axis=1), x[:, 0], atol=1e-13)
    assert s.w.min() >= -1e-15


def test_bernstein_is_not_interpolating():
    """Bernstein weights are not a Kronecker delta: at an element centre node the
    centre weight is 1/2 (the reason for its TLMPM-only use, review 3.5)."""
    grid = make_grid(1, cells=4)
    centre = grid.lower + 1.0 * grid.h          # node 1: the centre of element [0, 2h]
    _, s = evaluate("bernstein", centre[None], grid)
    weights = dict(zip(s.idx[0], s.w[0]))
    assert weights[1] == pytest.approx(0.5)
    assert weights[0] == pytest.approx(0.25) and weights[2] == pytest.approx(0.25)


def test_gimp_reduces_to_hat_functions_for_small_boxes():
    """As l_p -> 0 the uGIMP function becomes the hat function (review Fig. 17):
    the difference is O(l_p / h) (inside |d| < l/2 and near |d| = 1)."""
    grid = make_grid(1, cells=4)
    x = grid.lower + np.array([[1.3], [2.0], [2.75]]) * grid.h
    module = shape.get("gimp")
    stencil = make_stencil(3, 1, 3)
    spec = kernels.stencil_spec(1, 3)
    length = np.full((3, 1), 1e-6 * grid.h[0])
    module.weights(spec, x, length, grid.lower, grid.inv_h, grid.cells, grid.strides,
                   stencil.idx, stencil.w, stencil.dw, 1)
    d = (x - grid.node_positions()[stencil.idx][:, :, 0]) * grid.inv_h[0]
    np.testing.assert_allclose(stencil.w, np.maximum(0.0, 1.0 - np.abs(d[:, :, 0] if d.ndim == 3 else d)), atol=1e-6)


def test_cpgimp_boxes_follow_the_stretch():
    """cpGIMP with F = diag(0.5): a box of side h/4; at d = 1 - l/2 = 7/8 (the start
    of the outer piece) the weight is exactly the hat's 1 - d = 1/8."""
    grid = make_grid(1, cells=4)
    x = grid.lower + np.array([[2.0 + 7 / 8]]) * grid.h
    _, s = evaluate("cpgimp", x, grid, F=np.full((1, 1, 1), 0.5))
    weights = dict(zip(s.idx[0], s.w[0]))
    assert weights[2] == pytest.approx(1 / 8, abs=1e-14)
    # uGIMP (box h/2) at the same point is in its outer piece: (1 + 1/4 - 7/8)^2 / (2 * 1/2) = 9/64
    _, u = evaluate("gimp", x, grid)
    assert dict(zip(u.idx[0], u.w[0]))[2] == pytest.approx(9 / 64, abs=1e-14)


def test_quadratic_bspline_particles_needing_a_node_beyond_the_grid_are_reported():
    grid = make_grid(2)
    x = grid.lower + np.array([[3.0, 3.0], [3.0, 0.1], [2.0, 2.0]]) * grid.h
    outside, _ = evaluate("quadratic_bspline", x, grid)
    assert outside == 1


@pytest.mark.parametrize("name", ["gimp", "cpgimp"])
def test_gimp_boxes_are_cut_at_the_grid_ends(name):
    """A box crossing a grid end (a particle pressed against a wall) is cut there: the
    weights stay a partition of unity with gradients summing to 0, on existing nodes;
    only a particle whose centre leaves the grid is reported."""
    grid = make_grid(1, cells=4)
    s = np.array([0.0, 0.1, 0.2499, 3.9, 4.0])
    x = grid.lower + s[:, None] * grid.h
    outside, st = evaluate(name, x, grid)
    assert outside == -1
    np.testing.assert_allclose(st.w.sum(axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(st.dw.sum(axis=1), 0.0, atol=1e-12 * grid.inv_h[0])
    # the cut box [lower, x + l/2] averages N_0 = 1 - y: at s = 0 the box is [0, 1/4], weight 1 - 1/8
    assert st.w[0, 0] == pytest.approx(1 - 1 / 8)
    outside, _ = evaluate(name, grid.lower[None] - 0.01 * grid.h, grid)
    assert outside == 0


def test_gimp_matches_the_printed_pieces():
    """The piece-free form equals eqs. 3.12-3.13 for l_p = h/2 at every distance."""
    grid = make_grid(1, cells=6)
    l = 0.5
    s = np.linspace(1.6, 4.4, 281)
    x = grid.lower + s[:, None] * grid.h
    _, st = evaluate("gimp", x, grid)
    d = s[:, None] - st.idx            # (x_p - x_I) / h for the stencil nodes
    a = np.abs(d)
    phi = np.select([a < l / 2, a <= 1 - l / 2, a < 1 + l / 2],
                    [1 - (4 * d**2 + l**2) / (4 * l), 1 - a, (1 + l / 2 - a) ** 2 / (2 * l)], 0.0)
    dphi = np.select([a < l / 2, a <= 1 - l / 2, a < 1 + l / 2],
                     [-8 * d / (4 * l), -np.sign(d), -np.sign(d) * (1 + l / 2 - a) / l], 0.0) * grid.inv_h[0]
    np.testing.assert_allclose(st.w, phi, atol=1e-14)
    np.testing.assert_allclose(st.dw[:, :, 0], dphi, atol=1e-12 * grid.inv_h[0])


@pytest.mark.parametrize("name", ALL)
def test_support_sizes(name):
    """Nodes per axis: 2 (hats), 3 (GIMP with l_p <= h, quadratic B-splines and
    Bernstein), 4 (cubic B-splines); summary.py budgets memory with the same."""
    assert shape.get(name).SUPPORT == {"linear": 2, "cubic_bspline": 4}.get(name, 3) == shape.REGISTRY[name].support


def test_the_summary_budgets_the_registered_support(monkeypatch):
    """summary.particle_bytes reads the support from the registry: 8 bytes per weight,
    per index and per gradient component of each node a particle touches, where the general
    backend stores the stencil."""
    from solver import cost
    from solver.scene_checks import load_scene
    from solver.summary import particle_bytes

    scene = load_scene(Path(__file__).parents[2] / "examples" / "two_disks.json")   # 2D, linear
    monkeypatch.setattr(cost, "backend_name", lambda scene: "general")
    before = particle_bytes(scene)
    monkeypatch.setitem(shape.REGISTRY, "linear", replace(shape.REGISTRY["linear"], support=5))
    touched_more = 5**2 - 2**2
    assert particle_bytes(scene) - before == 8 * touched_more * (2 + scene.dimension)


@pytest.mark.parametrize("name", [name for name in ALL if shape.REGISTRY[name].apic_d is not None])
def test_the_declared_apic_constant_is_the_inertia_of_the_weights(name):
    """D_p = sum_I w_Ip (x_I - x_p)(x_I - x_p)^T = c h^2 I (eq. 5.38) at every position,
    c = apic_d: exact in exact arithmetic, so to round-off of the O(h^2) sums."""
    rng = np.random.default_rng(3)
    grid = make_grid(2)
    x = random_points(name, grid, 200, rng)
    _, s = evaluate(name, x, grid)
    offsets = grid.node_positions()[s.idx] - x[:, None, :]
    inertia = np.einsum("pk,pka,pkb->pab", s.w, offsets, offsets)
    expected = shape.REGISTRY[name].apic_d * np.diag(grid.h**2)
    np.testing.assert_allclose(inertia, np.broadcast_to(expected, inertia.shape), atol=1e-12 * np.max(grid.h) ** 2)


def test_a_tensor_shape_functions_weights_kernel_is_taken_from_numbas_cache_by_a_later_process():
    """The weights kernel generated per shape function (solver/shape/kernels/weights_template.py)
    is compiled once: a second process loads it from numba's cache instead of compiling it
    again (passed as an argument, the 1D function made every process compile it anew)."""
    import subprocess
    import sys
    probe = ("import numpy as np\n"
             "from solver.shape.kernels import gimp, tensor\n"
             "x = np.array([[0.35, 0.45]]); length = np.full((1, 2), 0.05)\n"
             "idx = np.zeros((1, 9), np.int64); w = np.zeros((1, 9)); dw = np.zeros((1, 9, 2))\n"
             "from solver.kernels import stencil_spec; spec = stencil_spec(2, 9)\n"
             "gimp.weights(spec, x, length, np.zeros(2), np.full(2, 10.0), np.array([10, 10]),\n"
             "             np.array([1, 11]), idx, w, dw, 1)\n"
             "weights = tensor.kernels('gimp').weights   # (a ThreadedKernel: either form counts)\n"
             "print(sum(sum(form.stats.cache_hits.values()) for form in (weights.parallel, weights.serial)))\n")
    runs = [subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=300)
            for _ in range(2)]
    for run in runs:
        assert run.returncode == 0, run.stderr
    assert int(runs[1].stdout.split()[-1]) >= 1   # the second process found the first one's entry
