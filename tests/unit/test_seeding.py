"""Geometry inside-tests and regular particle seeding ([R] 4.1, VERIFICATION_CASES A.14)."""

import math

import numpy as np
import pytest

from solver import seeding
from solver.geometry import Box, Cylinder, Difference, Intersection, Sphere, Union
from solver.scene_checks import load_scene
from solver.seeding import count_particles, seed

ELASTIC = {"model": "linear_elastic", "density": 1000, "youngs_modulus": 1000, "poisson_ratio": 0.3}


def scene_with(geometries, dimension=2, lower=None, upper=None, cell_size=0.05, ppc=2):
    lower = lower or [-0.5] * dimension
    upper = upper or [0.5] * dimension
    return load_scene({
        "dimension": dimension,
        "grid": {"lower": lower, "upper": upper, "cell_size": cell_size},
        "materials": {"m": ELASTIC},
        "bodies": [{"name": f"b{i}", "material": "m", "geometry": g, "particles_per_cell": ppc}
                   for i, g in enumerate(geometries)],
        "time": {"end": 1.0},
    })


def two_disks():
    """VERIFICATION_CASES E2: grid [-0.5, 0.5]^2, h = 0.05, disks R = 0.2, 2 x 2 per cell."""
    return scene_with([{"type": "sphere", "center": [-0.3, -0.3], "radius": 0.2},
                       {"type": "sphere", "center": [0.3, 0.3], "radius": 0.2}])


def full_lattice(scene, ppc):
    """Every particle position of the whole grid, written independently of seeding."""
    axes = [lo + (np.arange(n * ppc) + 0.5) * h / ppc
            for lo, n, h in zip(scene.grid_lower(), scene.grid_shape(), scene.cell_sizes())]
    mesh = np.meshgrid(*axes, indexing="ij")
    return np.stack([m.ravel() for m in mesh], axis=1)


class TestTwoDisks:
    def test_208_particles_per_disk(self):
        # VERIFICATION_CASES E2: 416 particles, 208 per disk
        assert count_particles(two_disks()) == [208, 208]

    def test_seeds(self):
        seeds = seed(two_disks())
        assert seeds.position.shape == (416, 2) and seeds.position.dtype == np.float64
        assert seeds.position.flags.c_contiguous
        assert seeds.body.dtype == np.int32
        np.testing.assert_array_equal(seeds.body, [0] * 208 + [1] * 208)
        np.testing.assert_array_equal(seeds.volume, np.full(416, 0.05**2 / 4))

    def test_particles_sit_at_quarter_and_three_quarter_cell(self):
        seeds = seed(two_disks())
        fraction = ((seeds.position + 0.5) / 0.05) % 1.0
        assert np.all(np.isclose(fraction, 0.25, atol=1e-9) | np.isclose(fraction, 0.75, atol=1e-9))

    def test_the_seeds_are_the_lattice_points_inside_each_disk(self):
        scene = two_disks()
        seeds = seed(scene)
        lattice = full_lattice(scene, 2)
        for index, center in enumerate([(-0.3, -0.3), (0.3, 0.3)]):
            expected = lattice[np.sum((lattice - center) ** 2, axis=1) <= 0.2**2]
            got = seeds.position[seeds.body == index]
            np.testing.assert_allclose(got, expected, atol=1e-12)


@pytest.mark.parametrize("dimension, geometry, inside", [
    (1, {"type": "sphere", "center": [0.05], "radius": 0.23},
     lambda p: np.abs(p[:, 0] - 0.05) <= 0.23),
    (3, {"type": "sphere", "center": [0.1, -0.05, 0.02], "radius": 0.31},
     lambda p: np.sum((p - [0.1, -0.05, 0.02]) ** 2, axis=1) <= 0.31**2),
    (3, {"type": "cylinder", "center": [0, 0.1, 0], "radius": 0.22, "axis": 0, "height": 0.63},
     lambda p: (np.abs(p[:, 0]) <= 0.315) & (np.hypot(p[:, 1] - 0.1, p[:, 2]) <= 0.22)),
    (3, {"type": "cylinder", "center": [0, 0, 0.05], "radius": 0.27, "height": 0.41},
     lambda p: (np.abs(p[:, 2] - 0.05) <= 0.205) & (np.hypot(p[:, 0], p[:, 1]) <= 0.27)),
    (2, {"type": "union", "parts": [{"type": "sphere", "center": [-0.2, 0], "radius": 0.17},
                                    {"type": "box", "lower": [0, -0.3], "upper": [0.3, 0.1]}]},
     lambda p: (np.hypot(p[:, 0] + 0.2, p[:, 1]) <= 0.17) | np.all((p >= [0, -0.3]) & (p <= [0.3, 0.1]), axis=1)),
    (2, {"type": "difference", "parts": [{"type": "box", "lower": [-0.4, -0.4], "upper": [0.4, 0.4]},
                                         {"type": "sphere", "center": [0, 0], "radius": 0.27}]},
     lambda p: np.all(np.abs(p) <= 0.4, axis=1) & (np.hypot(p[:, 0], p[:, 1]) > 0.27)),
    (2, {"type": "intersection", "parts": [{"type": "sphere", "center": [-0.1, 0], "radius": 0.33},
                                           {"type": "sphere", "center": [0.1, 0], "radius": 0.33}]},
     lambda p: (np.hypot(p[:, 0] + 0.1, p[:, 1]) <= 0.33) & (np.hypot(p[:, 0] - 0.1, p[:, 1]) <= 0.33)),
])
def test_seeds_are_the_lattice_points_inside_the_geometry(dimension, geometry, inside):
    scene = scene_with([geometry], dimension=dimension, cell_size=0.1, ppc=2)
    lattice = full_lattice(scene, 2)
    expected = lattice[inside(lattice)]
    assert len(expected) > 0
    np.testing.assert_allclose(seed(scene).position, expected, atol=1e-12)
    assert count_particles(scene) == [len(expected)]


def test_cell_aligned_box_is_filled_exactly():
    # 6 x 4 x 2 cells of 0.1 x 0.05 x 0.2 with 3 particles per axis: 48 * 27 particles
    scene = scene_with([{"type": "box", "lower": [0.1, 0.1, -0.2], "upper": [0.7, 0.3, 0.2]}], dimension=3,
                       lower=[0, 0, -0.4], upper=[1, 0.5, 0.4], cell_size=[0.1, 0.05, 0.2], ppc=3)
    seeds = seed(scene)
    assert len(seeds.volume) == 48 * 27
    assert seeds.volume[0] == pytest.approx(0.1 * 0.05 * 0.2 / 27, rel=1e-15)
    assert seeds.volume.sum() == pytest.approx(0.6 * 0.2 * 0.4, rel=1e-12)


def test_body_touching_the_grid_boundary():
    scene = scene_with([{"type": "box", "lower": [0.3, -0.5], "upper": [0.5, 0.5]}])
    assert count_particles(scene) == [4 * 20 * 4]


def test_bodies_keep_their_order():
    scene = scene_with([{"type": "box", "lower": [0.2, 0.2], "upper": [0.3, 0.3]},
                        {"type": "box", "lower": [-0.3, -0.3], "upper": [-0.2, -0.1]}])
    seeds = seed(scene)
    np.testing.assert_array_equal(seeds.body, [0] * 16 + [1] * 32)
    assert np.all(seeds.position[:16] > 0) and np.all(seeds.position[16:] < 0)


def test_small_chunks_give_the_same_seeds(monkeypatch):
    scene = two_disks()
    reference = seed(scene)
    monkeypatch.setattr(seeding, "CHUNK", 7)
    chunked = seed(scene)
    np.testing.assert_array_equal(chunked.position, reference.position)
    np.testing.assert_array_equal(chunked.body, reference.body)
    assert count_particles(scene) == [208, 208]


def test_counting_can_stop_above_a_limit(monkeypatch):
    monkeypatch.setattr(seeding, "CHUNK", 64)
    counts = count_particles(two_disks(), stop_above=100)
    assert 100 < sum(counts) <= 100 + 64
    assert counts[1] == 0


class TestGeometry:
    def test_boundaries_are_inside(self):
        box = Box(np.array([0.0, 0.0]), np.array([1.0, 2.0]))
        assert box.contains(np.array([[0.0, 2.0], [1.0, 0.5], [1.0 + 1e-12, 0.5]])).tolist() == [True, True, False]
        disk = Sphere(np.array([0.0, 0.0]), 0.5)
        assert disk.contains(np.array([[0.5, 0.0], [0.3, 0.4], [0.3, 0.41]])).tolist() == [True, True, False]
        cylinder = Cylinder(np.zeros(3), 1.0, 1, 2.0)
        assert cylinder.contains(np.array([[1.0, 1.0, 0.0], [0.0, -1.0, 1.0], [0.0, 1.01, 0.0]])).tolist() == [
            True, True, False]

    def test_bounding_boxes(self):
        cylinder = Cylinder(np.array([1.0, 2.0, 3.0]), 0.5, 0, 4.0)
        np.testing.assert_array_equal(np.array(cylinder.bounding_box()), [[-1.0, 1.5, 2.5], [3.0, 2.5, 3.5]])
        a = Box(np.array([0.0, 0.0]), np.array([2.0, 1.0]))
        b = Sphere(np.array([2.0, 1.0]), 0.5)
        np.testing.assert_array_equal(np.array(Union((a, b)).bounding_box()), [[0.0, 0.0], [2.5, 1.5]])
        np.testing.assert_array_equal(np.array(Intersection((a, b)).bounding_box()), [[1.5, 0.5], [2.0, 1.0]])
        np.testing.assert_array_equal(np.array(Difference((a, b)).bounding_box()), [[0.0, 0.0], [2.0, 1.0]])

    def test_difference_removes_every_later_part(self):
        points = np.array([[0.5], [1.5], [2.5], [3.5]])
        whole = Box(np.array([0.0]), np.array([4.0]))
        holes = (Box(np.array([1.0]), np.array([2.0])), Box(np.array([3.0]), np.array([4.0])))
        assert Difference((whole, *holes)).contains(points).tolist() == [True, False, True, False]


def test_scene_geometry_model_builds_its_shape():
    scene = two_disks()
    shape = scene.bodies[0].geometry.shape()
    assert isinstance(shape, Sphere) and shape.radius == 0.2
    assert math.isclose(shape.bounding_box()[1][0], -0.1)
