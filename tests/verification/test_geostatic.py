"""A soil column given its geostatic stress stays at rest under gravity.

Column of height H on a stick floor between slip walls (a laterally confined layer),
Drucker-Prager sand, k0 by default 1 - sin(phi) (Jaky). Reference: equilibrium,
sigma_yy = -rho g d, sigma_xx = sigma_zz = k0 sigma_yy, v = 0.

The MPM equilibrium is exact for this linear stress field: each particle's domain
(a quarter of a cell with two particles per cell and axis) lies inside one cell, where
the hats' gradients are constant, so the one-point quadrature integrates the linear
stress against them exactly, the body force against the linear hats too, and the
traction-free surface (half a spacing above the top particles) is where the stress is
zero, in a cell or on a grid line. So the velocities stay at round-off: below
1e-12 sqrt(g H) (4e-17 measured), where the same column started stress-free reaches
0.036 sqrt(g H) (the gravity shock)."""
import math

import numpy as np
import pytest

from solver.scene import SceneError
from solver.scene_checks import load_scene
from solver.stepper import ExplicitMPM

G, RHO, WIDTH = 9.81, 2000.0, 0.4
SAND = {"model": "drucker_prager", "density": RHO, "youngs_modulus": 1e7, "poisson_ratio": 0.3,
        "friction_angle": 30.0, "cohesion": 0.0}


def column(height, initial_stress, axisymmetric=False, material=SAND):
    scene = {"dimension": 2, "axisymmetric": axisymmetric,
             "grid": {"lower": [0, 0], "upper": [WIDTH, 1.2], "cell_size": 0.05},
             "materials": {"sand": material},
             "bodies": [{"name": "column", "material": "sand",
                         "geometry": {"type": "box", "lower": [0, 0], "upper": [WIDTH, height]}}],
             "boundary_conditions": [{"type": "wall", "face": "y-", "mode": "stick"},
                                     {"type": "wall", "face": "x-", "mode": "slip"},
                                     {"type": "wall", "face": "x+", "mode": "slip"}],
             "gravity": [0, -G], "time": {"end": 0.1}}
    if initial_stress is not None:
        scene["bodies"][0]["initial_stress"] = initial_stress
    return scene


def settle(scene, end=0.1):
    """Largest particle speed over the run (about eight P-wave transits of the column)."""
    sim = ExplicitMPM(load_scene(scene))
    fastest = 0.0
    while sim.time < end:
        sim.advance(sim.stable_time_step(0.5))
        fastest = max(fastest, float(np.abs(sim.particles.v).max()))
    return sim, fastest


@pytest.mark.parametrize("axisymmetric", [False, True], ids=["plane", "axisymmetric"])
def test_geostatic_column_stays_at_rest(axisymmetric):
    height = 1.0
    sim, fastest = settle(column(height, {"type": "geostatic"}, axisymmetric))
    p = sim.particles
    depth = height - p.x[:, 1]
    k0 = 1 - math.sin(math.radians(30.0))
    assert fastest < 1e-12 * math.sqrt(G * height)
    scale = RHO * G * height
    np.testing.assert_allclose(p.stress[:, 1, 1], -RHO * G * depth, rtol=0, atol=1e-12 * scale)
    for axis in (0, 2):
        np.testing.assert_allclose(p.stress[:, axis, axis], k0 * p.stress[:, 1, 1], rtol=0, atol=1e-12 * scale)
    assert np.abs(p.extra["plastic_strain"]).max() == 0.0


def test_geostatic_column_with_its_top_inside_a_cell_and_a_given_k0():
    height = 0.975                     # the top cell is half full
    _, geostatic = settle(column(height, {"type": "geostatic", "k0": 0.6}))
    _, shocked = settle(column(height, None))
    assert geostatic < 1e-12 * math.sqrt(G * height)
    assert shocked > 1e-2 * math.sqrt(G * height)      # what the initial stress prevents


def test_geostatic_stress_needs_gravity_and_k0():
    elastic = {"model": "linear_elastic", "density": RHO, "youngs_modulus": 1e7, "poisson_ratio": 0.3}
    scene = column(1.0, {"type": "geostatic"}, material=elastic)
    with pytest.raises(SceneError, match=r"bodies\[0\]\.initial_stress\.k0: required for a 'linear_elastic'"):
        load_scene(scene)
    scene = column(1.0, {"type": "geostatic"})
    scene["gravity"] = [1.0, -G]
    with pytest.raises(SceneError, match=r"bodies\[0\]\.initial_stress: a geostatic stress needs a gravity along one"):
        load_scene(scene)
