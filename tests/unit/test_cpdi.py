"""CPDI-R4 weights (solver/shape/kernels/cpdi.py): review 3.6, spec B.5, E27, E28.

Tolerances: the weights are sums of a few O(1) products, so identities hold to
round-off (1e-12); gradients scale with 1/h."""
from types import SimpleNamespace

import numpy as np
import pytest
from test_shape_functions import evaluate, make_grid

from solver import kernels, shape
from solver.state import make_stencil


def _random_F(n, dim, rng, spread=0.3):
    """Deformation gradients with det > 0, stretch and shear up to `spread`."""
    F = np.eye(dim)[None] + rng.uniform(-spread, spread, size=(n, dim, dim))
    F[np.linalg.det(F) < 0.2] = np.eye(dim)
    return F


def _inside(grid, n, rng, margin):
    s = rng.uniform(margin, grid.cells - margin, size=(n, len(grid.h)))
    return grid.lower + s * grid.h


@pytest.mark.parametrize("dim", [1, 2, 3])
def test_partition_of_unity_and_linear_reproduction_with_deformed_domains(dim):
    """eq. 3.33: weights sum to 1, gradients to 0; sum_I phi_I x_I = x_p and
    sum_I x_I (x) grad phi_I = I (the gradient of a linear field is exact), for
    parallelograms sheared and stretched by F (entries of F - I up to 0.3: the domain of
    side h/2 reaches at most 0.4 h from x_p), a cell away from the grid ends."""
    rng = np.random.default_rng(2 + dim)
    grid = make_grid(dim)
    x = _inside(grid, 300, rng, 1.0)
    F = _random_F(len(x), dim, rng)
    outside, s = evaluate("cpdi_r4", x, grid, F)
    assert outside == -1
    _assert_unity_and_linear(s, grid, x, gradient_sum=1e-12)


def _assert_unity_and_linear(s, grid, centre, gradient_sum):
    """Weights sum to 1 (non-negative) and gradients to 0 (`gradient_sum` per 1/h);
    sum_I phi_I x_I = centre and sum_I x_I (x) grad phi_I = I."""
    n, dim = centre.shape
    nodes = grid.node_positions()[s.idx]
    np.testing.assert_allclose(s.w.sum(axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(s.dw.sum(axis=1), 0.0, atol=gradient_sum * np.max(grid.inv_h))
    np.testing.assert_allclose(np.einsum("pk,pka->pa", s.w, nodes), centre, atol=1e-12)
    np.testing.assert_allclose(np.einsum("pka,pkb->pab", nodes, s.dw),
                               np.broadcast_to(np.eye(dim), (n, dim, dim)), atol=1e-11)
    assert np.all(s.w >= -1e-15)


def test_2d_matches_the_printed_formula():
    """Eq. 3.32 as the spec (B.5) prints it: phi_I = 1/4 sum_c N_I(x_c) and
    grad phi_I = 1/V_p {(N_I(x1) - N_I(x3)) [r1y - r2y, r2x - r1x] + (N_I(x2) - N_I(x4)) [r1y + r2y, -r1x - r2x]},
    corners counter-clockwise, V_p = 4 |r1 x r2|, with N_I the bilinear hats."""
    rng = np.random.default_rng(7)
    grid = make_grid(2)
    x = _inside(grid, 50, rng, 1.0)
    F = _random_F(len(x), 2, rng)
    _, s = evaluate("cpdi_r4", x, grid, F)
    l0 = grid.h / 2
    for p in range(len(x)):
        r1, r2 = F[p] @ [0.5 * l0[0], 0.0], F[p] @ [0.0, 0.5 * l0[1]]
        corners = [x[p] - r1 - r2, x[p] + r1 - r2, x[p] + r1 + r2, x[p] - r1 + r2]
        V = 4 * abs(r1[0] * r2[1] - r1[1] * r2[0])
        nodes = grid.node_positions()[s.idx[p]]
        N = np.array([[np.prod(np.maximum(0, 1 - np.abs(c - n) / grid.h)) for n in nodes] for c in corners])
        np.testing.assert_allclose(s.w[p], N.mean(axis=0), atol=1e-13)
        grad = (np.outer(N[0] - N[2], [r1[1] - r2[1], r2[0] - r1[0]])
                + np.outer(N[1] - N[3], [r1[1] + r2[1], -r1[0] - r2[0]])) / V
        np.testing.assert_allclose(s.dw[p], grad, atol=1e-10 * np.max(grid.inv_h))


def test_e27_cpdi_l2_partition_of_unity_fails_only_near_the_grid_ends_without_extra_cells():
    """E27: 3 cells of h = 1 (nodes 1-4 at 0..3), one particle of l_p = h sweeping from
    node 1 to node 4. The review's CPDI-L2 (no extra cells): the weights on nodes 1-4 sum
    to 1 except for 0 <= x < 0.5 and 2.5 < x <= 3, where an end of the particle lies
    outside the 3 cells. Computed on a wider grid (cells on either side) and summed over
    nodes 1-4 only, which is the 3-cell grid without extra cells. On the 3-cell grid
    itself the ends are moved onto the grid (solver/shape/kernels/cpdi.py): the sum is 1
    everywhere."""
    wide = make_grid(1, cells=5, h=1.0)
    wide.lower[:] = -1.0                      # nodes at -1..4; the review's nodes 1-4 at 0..3
    x = np.linspace(0.0, 3.0, 61)[:, None]
    F = np.ones((len(x), 1, 1))
    length = np.full((len(x), 1), 1.0)         # l_p = h
    module = shape.get("cpdi_r4")
    for grid, lower_node in ((wide, 1), (make_grid(1, cells=3, h=1.0), 0)):
        if grid is not wide:
            grid.lower[:] = 0.0
        stencil = make_stencil(len(x), 1, 4)
        particles = SimpleNamespace(F=F, extra={"domain_length": length})
        assert shape.evaluate(module, kernels.stencil_spec(1, 4), x, particles, grid, stencil) == -1
        on_1_to_4 = np.where((stencil.idx >= lower_node) & (stencil.idx <= lower_node + 3), stencil.w, 0).sum(axis=1)
        if grid is wide:
            fails = np.abs(on_1_to_4 - 1) > 1e-12
            expected = (x[:, 0] < 0.5 - 1e-12) | (x[:, 0] > 2.5 + 1e-12)
            assert np.array_equal(fails, expected)
            # and the weights there are what is left of the end beyond the grid: 1 - (0.5 - x) / 2 at the left
            left = x[:, 0] < 0.5
            np.testing.assert_allclose(on_1_to_4[left], 1 - 0.5 * (0.5 - x[left, 0]), atol=1e-12)
            # not interpolating: at node 2 (x = 1, ends at 0.5 and 1.5) the weight on node 2 is 1/2, not 1
            at_node = np.argmin(np.abs(x[:, 0] - 1.0))
            assert np.max(stencil.w[at_node]) == pytest.approx(0.5)
        else:
            np.testing.assert_allclose(on_1_to_4, 1.0, atol=1e-12)


def test_e28_a_domain_wider_than_the_stencil_is_reported_naming_its_size():
    """E28: a domain spanning more than the three cells around the particle's own (here
    a box of h/2 stretched 8x along x: 4 cells) is refused by the weights, and `failure`
    tells it from a particle outside the grid; 3.8x (1.9 cells) is accepted."""
    grid = make_grid(2, cells=8, h=0.25)
    x = (grid.lower + 4.5 * grid.h)[None, :].repeat(2, axis=0)
    F = np.array([np.diag([8.0, 1.0]), np.diag([3.8, 1.0])])
    module = shape.get("cpdi_r4")
    outside, _ = evaluate("cpdi_r4", x[:1], grid, F[:1])
    assert outside == 0
    particles = SimpleNamespace(F=F, extra={"domain_length": np.repeat(grid.h[None] / 2, 2, axis=0)})
    quantity, detail = shape.failure(module, x, particles, grid, 0)
    assert quantity == "particle domain (cpdi)" and "spans [4." in detail
    assert evaluate("cpdi_r4", x[1:], grid, F[1:])[0] == -1
    outside_grid = x.copy()
    outside_grid[0, 0] = grid.lower[0] - 0.1
    assert shape.failure(module, outside_grid, particles, grid, 0) is None


def _scene(**method):
    return {"version": 1, "name": "cpdi", "dimension": 2, "method": {"shape_function": "cpdi_r4", **method},
            "grid": {"lower": [0.0, 0.0], "upper": [1.0, 1.0], "cell_size": 0.25},
            "materials": {"m": {"model": "linear_elastic", "density": 1, "youngs_modulus": 1, "poisson_ratio": 0.3}},
            "bodies": [{"name": "b", "material": "m", "particles_per_cell": 2,
                        "geometry": {"type": "box", "lower": [0.25, 0.25], "upper": [0.5, 0.5]}}],
            "time": {"end": 1.0}}


@pytest.mark.parametrize("change,path,words", [
    ({"method": {"shape_function": "cpdi_r4", "formulation": "tlmpm"}}, "method.shape_function", "only supported with formulation 'ulmpm'"),
    ({"axisymmetric": True}, "method.shape_function", "not supported in axisymmetric scenes"),
])
def test_refused_where_the_review_gives_no_cpdi(change, path, words):
    from solver.scene import SceneError
    from solver.scene_checks import load_scene
    scene = {**_scene(), **change}
    with pytest.raises(SceneError) as error:
        load_scene(scene)
    assert any(e["path"] == path and words in e["message"] for e in error.value.errors), error.value.errors


def test_particle_domain_field_is_the_seeded_box_carried_by_F():
    """Corners x_p + F diag(l0/2) s_c (axis 0 fastest), l0 = h / particles_per_cell."""
    from solver.fields import field
    from solver.scene_checks import load_scene
    from solver.stepper import ExplicitMPM
    sim = ExplicitMPM(load_scene(_scene()))
    p = sim.particles
    p.F[:] = [[1.5, 0.2], [0.0, 0.8]]
    corners = field("particle_domain")(sim).reshape(p.count, 4, 2)
    half = 0.25 / 2 / 2
    for c, (sx, sy) in enumerate([(-1, -1), (1, -1), (-1, 1), (1, 1)]):
        np.testing.assert_allclose(corners[:, c], p.x + np.array([1.5 * sx + 0.2 * sy, 0.8 * sy]) * half, atol=1e-15)


def _evaluate_tracked(x, corners, grid):
    """cpdi_q4 (2D) or cpdi_tet4 (3D) on the given tracked corners."""
    dim = x.shape[1]
    module = shape.get({2: "cpdi_q4", 3: "cpdi_tet4"}[dim])
    stencil = make_stencil(len(x), dim, 4)
    particles = SimpleNamespace(extra={"domain_corners": np.ascontiguousarray(corners)})
    outside = shape.evaluate(module, kernels.stencil_spec(dim, 4 ** dim), np.ascontiguousarray(x), particles, grid,
                             stencil)
    return outside, stencil


def test_q4_on_a_parallelogram_is_r4():
    """A quadrilateral that is a parallelogram has a = b = 0 in eq. 3.36: the weights are
    1/4 each and eq. 3.37 is eq. 3.32, so Q4 and R4 agree (to round-off)."""
    from solver.shape.kernels.cpdi import domain_corners
    rng = np.random.default_rng(17)
    grid = make_grid(2)
    x = _inside(grid, 100, rng, 1.0)
    F = _random_F(len(x), 2, rng)
    corners = domain_corners(x, np.repeat(grid.h[None] / 2, len(x), axis=0), F)[:, [0, 1, 3, 2]]   # counter-clockwise
    _, r4 = evaluate("cpdi_r4", x, grid, F)
    outside, q4 = _evaluate_tracked(x, corners, grid)
    assert outside == -1
    np.testing.assert_array_equal(q4.idx, r4.idx)
    np.testing.assert_allclose(q4.w, r4.w, atol=1e-13)
    np.testing.assert_allclose(q4.dw, r4.dw, atol=1e-11 * np.max(grid.inv_h))


def test_q4_on_random_quadrilaterals_reproduces_the_centroid_and_linear_gradients():
    """For a general convex quadrilateral: weights sum to 1 and gradients to 0, sum_I phi_I x_I
    is the domain's centroid (the weights average the hats over the domain, eq. 3.36; the
    spec checked them against the exact integrals) and sum_I x_I (x) grad phi_I = I."""
    rng = np.random.default_rng(23)
    grid = make_grid(2)
    x = _inside(grid, 200, rng, 1.0)
    square = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float)
    corners = x[:, None, :] + (square[None] + rng.uniform(-0.3, 0.3, size=(len(x), 4, 2))) * grid.h / 4
    outside, s = _evaluate_tracked(x, corners, grid)
    assert outside == -1
    nodes = grid.node_positions()[s.idx]
    np.testing.assert_allclose(s.w.sum(axis=1), 1.0, atol=1e-12)
    np.testing.assert_allclose(s.dw.sum(axis=1), 0.0, atol=1e-11 * np.max(grid.inv_h))
    np.testing.assert_allclose(np.einsum("pka,pkb->pab", nodes, s.dw),
                               np.broadcast_to(np.eye(2), (len(x), 2, 2)), atol=1e-11)
    # the centroid of each quadrilateral, from its two triangles
    a, b, c, d = (corners[:, i] for i in range(4))
    def cross(u, v):
        return u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0]
    area1, area2 = 0.5 * np.abs(cross(b - a, c - a)), 0.5 * np.abs(cross(c - a, d - a))
    centroid = ((a + b + c) / 3 * area1[:, None] + (a + c + d) / 3 * area2[:, None]) / (area1 + area2)[:, None]
    np.testing.assert_allclose(np.einsum("pk,pka->pa", s.w, nodes), centroid, atol=1e-12)


def test_q4_is_refused_outside_2d():
    from solver.scene import SceneError
    from solver.scene_checks import load_scene
    scene = _scene(shape_function="cpdi_q4")
    load_scene(scene)
    scene.update(dimension=3, grid={"lower": [0, 0, 0], "upper": [1, 1, 1], "cell_size": 0.25})
    scene["bodies"][0]["geometry"] = {"type": "box", "lower": [0.25] * 3, "upper": [0.5] * 3}
    with pytest.raises(SceneError) as error:
        load_scene(scene)
    assert any(e["path"] == "method.shape_function" and "2D" in e["message"] for e in error.value.errors)


# --------------------------------------------------------------------------- CPDI-Tet4

def _kuhn_volumes_and_centroids(corners):
    """The six tetrahedra {0, e_i, e_i + e_j, 7} of each hexahedron (corners axis 0 fastest),
    written here with numpy's determinant, signed by the parity of the axis order (i, j, k)
    so that an unfolded domain's are positive: (n, 6) volumes and (n, 6, 3) centroids."""
    from itertools import permutations
    orders = list(permutations(range(3)))
    tets = [[0, 1 << i, (1 << i) | (1 << j), 7] for i, j, _ in orders]
    parity = np.array([np.linalg.det(np.eye(3)[list(order)]) for order in orders])
    v = corners[:, tets]                                   # (n, 6, 4, 3)
    edges = np.swapaxes(v[:, :, 1:] - v[:, :, :1], 2, 3)   # edge vectors as columns
    return parity * np.linalg.det(edges) / 6, v.mean(axis=2)


def test_tet4_partition_of_unity_and_linear_reproduction_on_distorted_hexahedra():
    """Each domain a hexahedron of side h/2 with every corner moved by up to 0.15 of that side
    (convex enough that all six tetrahedra keep a positive volume): the weights sum to 1
    and the gradients to 0; sum_I phi_I x_I is the domain's volume centroid (the weights are the
    domain averages of the hats' linear interpolants on the tetrahedra, [R] 3.6.3) and
    sum_I x_I (x) grad phi_I = I (a linear field's gradient is exact). Round-off: 1e-12."""
    from solver.shape.kernels.cpdi import domain_corners
    rng = np.random.default_rng(41)
    grid = make_grid(3)
    x = _inside(grid, 200, rng, 1.0)
    side = np.repeat(grid.h[None] / 2, len(x), axis=0)
    box = domain_corners(x, side, np.broadcast_to(np.eye(3), (len(x), 3, 3)))
    corners = box + rng.uniform(-0.15, 0.15, size=box.shape) * side[:, None, :]
    volumes, centroids = _kuhn_volumes_and_centroids(corners)
    assert np.all(volumes > 0)
    centroid = np.einsum("pt,pta->pa", volumes, centroids) / volumes.sum(axis=1)[:, None]
    outside, s = _evaluate_tracked(x, corners, grid)
    assert outside == -1
    _assert_unity_and_linear(s, grid, centroid, gradient_sum=1e-11)


def test_tet4_refuses_a_folded_domain():
    """A hexahedron with two corners swapped has tetrahedra of negative volume: the weights
    stop at that particle rather than give negative masses."""
    from solver.shape.kernels.cpdi import domain_corners
    grid = make_grid(3)
    x = _inside(grid, 3, np.random.default_rng(3), 1.0)
    side = np.repeat(grid.h[None] / 2, len(x), axis=0)
    corners = domain_corners(x, side, np.broadcast_to(np.eye(3), (len(x), 3, 3)))
    corners[1, [0, 7]] = corners[1, [7, 0]]
    outside, _ = _evaluate_tracked(x, corners, grid)
    assert outside == 1



def test_tet4_refuses_a_domain_beyond_its_stencil():
    """E28 for CPDI-Tet4: a domain stretched to 5 cells along x (its corners beyond the
    cells next to the particle's own) stops at that particle."""
    from solver.shape.kernels.cpdi import domain_corners
    grid = make_grid(3, cells=12)
    x = grid.lower + 6.0 * grid.h + 0.1 * grid.h
    x = np.repeat(x[None], 2, axis=0)
    side = np.repeat(grid.h[None] / 2, 2, axis=0)
    side[1, 0] = 5.0 * grid.h[0]
    corners = domain_corners(x, side, np.broadcast_to(np.eye(3), (2, 3, 3)))
    outside, _ = _evaluate_tracked(x, corners, grid)
    assert outside == 1


def _scene_3d(**method):
    scene = _scene(**method)
    scene.update(dimension=3, grid={"lower": [0, 0, 0], "upper": [1, 1, 1], "cell_size": 0.125},
                 gravity=[0.0, 0.0, -10.0], boundary_conditions=[{"type": "wall", "face": "z-", "mode": "slip"}],
                 time={"end": 0.25, "dt": 1e-3})
    scene["bodies"][0]["geometry"] = {"type": "box", "lower": [0.25, 0.25, 0.0], "upper": [0.75, 0.75, 0.5]}
    scene["materials"]["m"].update(youngs_modulus=2000.0, density=100.0)
    return scene


def test_tet4_3d_run_tracks_the_domains_and_keeps_each_particle_at_its_centroid():
    """A soft block settling on a slip floor under gravity (250 steps): the corners move
    (the block sags), the particle sits at its hexahedron's volume centroid (eq. 3.39), the
    domains still tile the block (their volumes sum to the volume of the block's hull of
    corners, which a gap or an overlap would change: checked as the sum against the sum of the
    particles' V = V0 det F, equal to O(strain^2) -- 1e-3 here), and the `particle_domain` field
    is the tracked corners."""
    from solver.fields import field
    from solver.scene_checks import load_scene
    from solver.stepper import ExplicitMPM
    sim = ExplicitMPM(load_scene(_scene_3d(shape_function="cpdi_tet4")))
    p = sim.particles
    start = p.extra["domain_corners"].copy()
    for _ in range(250):
        sim.advance(1e-3)
    corners = p.extra["domain_corners"]
    assert np.max(np.abs(corners - start)) > 1e-3               # they moved (the block sagged ~ rho g H^2 / E)
    volumes, centroids = _kuhn_volumes_and_centroids(corners)
    np.testing.assert_allclose(np.einsum("pt,pta->pa", volumes, centroids) / volumes.sum(axis=1)[:, None], p.x,
                               atol=1e-12)
    assert abs(volumes.sum() / p.volume.sum() - 1) < 1e-3
    np.testing.assert_array_equal(field("particle_domain")(sim).reshape(p.count, 8, 3), corners)


def test_tet4_is_refused_outside_3d():
    from solver.scene import SceneError
    from solver.scene_checks import load_scene
    with pytest.raises(SceneError) as error:
        load_scene(_scene(shape_function="cpdi_tet4"))
    assert any(e["path"] == "method.shape_function" and "3D" in e["message"] for e in error.value.errors)


def _state(sim):
    p = sim.particles
    return [p.x, p.v, p.F, p.stress, p.volume] + ([p.extra["domain_corners"]] if "domain_corners" in p.extra else [])


@pytest.mark.parametrize("shape_function,dim", [("cpdi_r4", 2), ("cpdi_q4", 2), ("cpdi_r4", 3), ("cpdi_tet4", 3)])
def test_compact_stencil_gives_the_wide_stencils_results_bit_for_bit(shape_function, dim):
    """The step starts on the compact stencil (3 nodes per axis, the nodes of the two cells
    per axis the corners lie in); it holds the wide one's (4 per axis) nonzero entries in the
    same order, so every sum in the transfers adds the same terms in the same order: the
    particles come out equal bit for bit (a run on the wide stencil from the start against
    one on the compact stencil, 30 steps of a block falling onto a slip floor)."""
    from solver.scene_checks import load_scene
    from solver.stepper import ExplicitMPM
    scene = _scene_3d(shape_function=shape_function) if dim == 3 else {
        **_scene(shape_function=shape_function), "gravity": [0.0, -10.0],
        "boundary_conditions": [{"type": "wall", "face": "y-", "mode": "slip"}]}
    compact, wide = ExplicitMPM(load_scene(scene)), ExplicitMPM(load_scene(scene))
    wide.phases._widen_stencil()
    assert compact.stencil.w.shape[1] == 3 ** dim and wide.stencil.w.shape[1] == 4 ** dim
    for _ in range(30):
        compact.advance(1e-3)
        wide.advance(1e-3)
    assert compact.stencil_support == 3   # (never widened: the domains stayed within two cells)
    for a, b in zip(_state(compact), _state(wide)):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("stretch,grid_lower,support", [(3.8, 0.0, 4), (7.6, -1.0, 6)])
def test_a_domain_outgrowing_the_stencil_widens_it_as_far_as_it_needs_for_the_rest_of_the_run(
        stretch, grid_lower, support):
    """A domain (a box of h/2 about x = 0.3125) stretched mid-run: to 1.9 cells (its corners
    in three cells along x) the step widens the stencil to 4 nodes per axis; to 3.8 cells
    (corners at -0.1625 and 0.7875, in cells 3 and 7 of a grid from -1) to the 6 its corners
    span, instead of stopping. Either way it goes on with the same bits as a run that had
    that stencil from the start."""
    from solver.scene_checks import load_scene
    from solver.stepper import ExplicitMPM
    scene = load_scene({**_scene(), "grid": {"lower": [grid_lower, 0.0], "upper": [1.0 - 3 * grid_lower, 1.0],
                                             "cell_size": 0.25}})
    grown, wide = ExplicitMPM(scene), ExplicitMPM(scene)
    wide.phases._widen_stencil(support)
    assert grown.particles.x[0] == pytest.approx([0.3125, 0.3125])
    for step in range(20):
        if step == 5:
            for sim in (grown, wide):
                sim.particles.F[0] = np.diag([stretch, 1.0])
        grown.advance(1e-3)
        wide.advance(1e-3)
        assert grown.stencil_support == (3 if step < 5 else support)
    assert grown.stencil.w.shape[1] == support ** 2 and grown.wide_support == support
    for a, b in zip(_state(grown), _state(wide)):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("dim", [1, 2])
def test_domains_stretched_over_several_cells_keep_unity_and_linear_reproduction(dim):
    """A stencil of S nodes per axis, S from `support_needed`, holds domains of any size
    (up to the kernels' widest stencil: 2D here, 3D stops at 4 nodes per axis):
    boxes of h/2 stretched up to 9x along an axis (4.5 cells) and sheared, well inside the
    grid, give weights that sum to 1, gradients that sum to 0 and reproduce linear fields
    (eq. 3.33 holds for any domain: the corners' hats do), as on the 4-node stencil."""
    from solver.shape.kernels.cpdi import support_needed
    rng = np.random.default_rng(31 + dim)
    grid = make_grid(dim, cells=16, h=0.25)
    x = _inside(grid, 100, rng, 6.0)
    F = _random_F(len(x), dim, rng)
    F[:, 0, 0] = rng.uniform(5.0, 9.0, size=len(x))
    module = shape.get("cpdi_r4")
    particles = SimpleNamespace(F=F, extra={"domain_length": np.repeat(grid.h[None] / 2, len(x), axis=0)})
    support = support_needed(x, particles, grid)
    assert support >= 6   # (4 cells and more: the domains outgrew the 4-node stencil)
    narrow = make_stencil(len(x), dim, 4)
    assert shape.evaluate(module, kernels.stencil_spec(dim, 4 ** dim), x, particles, grid, narrow) >= 0
    stencil = make_stencil(len(x), dim, support)
    assert shape.evaluate(module, kernels.stencil_spec(dim, support ** dim), x, particles, grid, stencil) == -1
    _assert_unity_and_linear(stencil, grid, x, gradient_sum=1e-12)
