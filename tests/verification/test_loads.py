"""Loads, damping and polygons (issue 19): surface particles, a traction bar, a
cantilever under a tip force, the work of damping, a polygon's mass.

References are derived in each test; the numbers are in docs/benchmarks.md.
"""
from __future__ import annotations

import copy
import json
import math
from pathlib import Path

import numpy as np
import pytest

from solver.loads import AppliedLoads
from solver.scene import SceneError
from solver.scene_checks import load_scene
from solver.seeding import seed
from solver.stepper import ExplicitMPM
from solver.surface import surface_areas

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
E, NU, RHO = 1e6, 0.3, 1000.0
E_PLANE = E / (1 - NU**2)   # 2D scenes are plane strain (sigma_zz = lambda tr eps)


def bar(**extra) -> dict:
    """A 1 x 0.1 elastic strip on a 2.5 cm grid, 2 x 2 particles per cell."""
    scene = {
        "dimension": 2, "method": {"scheme": "musl", "shape_function": "linear", "transfer": "flip"},
        "grid": {"lower": [0.0, 0.3], "upper": [1.2, 0.7], "cell_size": 0.025},
        "materials": {"m": {"model": "linear_elastic", "density": RHO, "youngs_modulus": E, "poisson_ratio": NU}},
        "bodies": [{"name": "beam", "material": "m", "particles_per_cell": 2,
                    "geometry": {"type": "box", "lower": [0.1, 0.45], "upper": [1.1, 0.55]}}],
        "time": {"end": 1.0, "cfl": 0.5},
    }
    scene.update(extra)
    return scene


def run_until(sim, end: float) -> None:
    while sim.time < end - 1e-12:
        sim.advance(min(sim.stable_time_step(0.5), end - sim.time))


# -- surface particles ---------------------------------------------------------------------

def test_traction_on_a_box_face_sums_to_traction_times_length():
    """Every particle of the right face (corners included) carries one lattice face,
    h / ppc long: the face's particles carry its length, 0.1, exactly."""
    scene = load_scene(bar(loads=[{"type": "traction", "body": "beam",
                                   "where": {"type": "box", "lower": [1.09, 0.4], "upper": [1.2, 0.6]},
                                   "traction": [3.0, "2 * t"]}]))
    sim = ExplicitMPM(scene)
    share = sim.particles.extra[AppliedLoads.SHARE][:, 0]
    assert np.count_nonzero(share) == 8   # the 8 particles of the face (the box reaches no other column)
    force = share.sum() * sim.applied_loads.values(0.5)[0]
    np.testing.assert_allclose(force, [3.0 * 0.1, 1.0 * 0.1], rtol=1e-12)


def test_axisymmetric_loads_act_on_rings():
    """An axisymmetric cylinder (x = r): its top face's particles are rings, so a traction t
    on it sums to t pi R^2 (exact: the ring areas 2 pi r_p h/ppc at the midpoints r_p sum to
    pi R^2), each particle's share grows as its radius, and a force load is shared by ring
    mass. (Shared by plane lengths, the traction summed to t R and pressed the axis hardest.)"""
    radius, top = 0.1, 0.55
    cylinder = bar(axisymmetric=True,
                   grid={"lower": [0.0, 0.3], "upper": [0.2, 0.7], "cell_size": 0.025},
                   bodies=[{"name": "beam", "material": "m", "particles_per_cell": 2,
                            "geometry": {"type": "box", "lower": [0.0, 0.45], "upper": [radius, top]}}],
                   loads=[{"type": "traction", "body": "beam",
                           "where": {"type": "box", "lower": [0.0, top - 0.01], "upper": [0.2, 0.7]},
                           "traction": [0.0, -1000.0]},
                          {"type": "force", "body": "beam",
                           "where": {"type": "box", "lower": [0.0, top - 0.01], "upper": [0.2, 0.7]},
                           "force": [0.0, -1.0]}])
    sim = ExplicitMPM(load_scene(cylinder))
    p = sim.particles
    traction, force = p.extra[AppliedLoads.SHARE][:, 0], p.extra[AppliedLoads.SHARE][:, 1]
    loaded = traction > 0
    assert np.count_nonzero(loaded) == 8   # the top row: 4 cells x 2 particles across r
    np.testing.assert_allclose(traction.sum(), math.pi * radius**2, rtol=1e-12)
    np.testing.assert_allclose(traction[loaded] / p.x[loaded, 0], traction[loaded][0] / p.x[loaded, 0][0], rtol=1e-12)
    np.testing.assert_allclose(force[loaded], p.mass[loaded] / p.mass[loaded].sum(), rtol=1e-12)   # ring masses now


def test_disk_surface_lies_on_the_circle_and_a_pressure_has_no_net_force():
    """A disk of radius 0.3 seeded 2 x 2 per 2 cm cell: the surface particles lie within
    one cell inside the circle; the outward area vectors sum to zero exactly, so a
    uniform pressure -p a_p has no net force; the areas sum to 0.875 of the perimeter
    (the staircase's particles carry one face each: between 1/sqrt(2) and 1 of the
    true length, documented in solver/surface.py)."""
    scene = load_scene({
        "dimension": 2, "grid": {"lower": [0, 0], "upper": [1, 1], "cell_size": 0.02},
        "materials": {"m": {"model": "linear_elastic", "density": 1, "youngs_modulus": 1, "poisson_ratio": 0}},
        "bodies": [{"name": "disk", "material": "m", "geometry": {"type": "sphere", "center": [0.5, 0.5], "radius": 0.3}}],
        "time": {"end": 1},
    })
    seeds = seed(scene)
    vector, area = surface_areas(seeds.position, seeds.volume, scene.grid_lower(), [0.01, 0.01])
    radius = np.linalg.norm(seeds.position[area > 0] - 0.5, axis=1)
    assert radius.max() <= 0.3 and radius.min() >= 0.3 - 0.02
    pressure = 1e5
    assert np.all(np.abs((-pressure * vector).sum(axis=0)) <= 1e-9 * pressure * area.sum())
    assert 0.85 < area.sum() / (2 * math.pi * 0.3) < 0.92


# -- the traction bar ----------------------------------------------------------------------

def test_traction_bar_at_rest_carries_the_traction_as_stress():
    """A strip held axially at its left end (x velocity 0 on the nodes at x <= 0.1),
    pulled by t = 1000 Pa on its right face, settles with local damping: sigma_xx = t
    through the strip. Away from the ends (where the nodal mass of the end cells and
    the clamp disturb the field) the mean is within 2 % (measured 0.5 %)."""
    t = 1000.0
    scene = load_scene(bar(
        boundary_conditions=[{"type": "velocity", "where": {"type": "box", "lower": [0, 0.3], "upper": [0.1, 0.7]},
                              "velocity": [0, None]}],
        loads=[{"type": "traction", "body": "beam", "where": {"type": "box", "lower": [1.09, 0.4], "upper": [1.2, 0.6]},
                "traction": [f"{t} * min(t / 0.1, 1)", 0]}],
        damping={"type": "local", "coefficient": 0.5}))
    sim = ExplicitMPM(scene)
    run_until(sim, 0.6)
    p = sim.particles
    middle = (p.x[:, 0] > 0.3) & (p.x[:, 0] < 0.9)
    sxx = p.stress[middle, 0, 0].mean()
    assert abs(sxx / t - 1) < 0.02, sxx


# -- the cantilever ------------------------------------------------------------------------

def cantilever_deflection(cell: float, end: float) -> tuple[float, float]:
    """The tip deflection of examples/cantilever_2d.json at rest (cell size `cell`), and
    the Euler-Bernoulli + Timoshenko shear reference."""
    data = json.loads((EXAMPLES / "cantilever_2d.json").read_text())
    data["grid"]["cell_size"] = cell
    data["loads"][0]["where"]["lower"][0] = 1.1 - cell / 2   # the tip column of particles
    sim = ExplicitMPM(load_scene(data))
    x0 = sim.particles.x.copy()
    tip = x0[:, 0] > 1.1 - cell / 2
    run_until(sim, end)
    deflection = float(np.mean(sim.particles.x[tip, 1] - x0[tip, 1]))
    P, L, H = 2.75, 1.0, 0.1
    inertia, shear = H**3 / 12, E / (2 * (1 + NU))
    reference = P * L**3 / (3 * E_PLANE * inertia) + P * L / (5 / 6 * shear * H)
    return -deflection, reference


def test_cantilever_tip_deflection():
    """A 1 x 0.1 cantilever (plane strain, 4 cells through the depth, 2 x 2 particles
    per cell) under a 2.75 N tip force ramped over 0.5 s, settled with local damping
    0.3 for 4 s: tip deflection against P L^3 / (3 E' I) + P L / (kappa G A) (E' = E /
    (1 - nu^2), kappa = 5/6; the shear term is 0.9 %). Linear shape functions with 4
    cells through the depth are a little stiff in bending and the clamp is the node
    column at x <= 0.1 (the support is not perfectly rigid at the particle level):
    within 6 %."""
    measured, reference = cantilever_deflection(0.025, 4.0)
    assert abs(measured / reference - 1) < 0.06, (measured, reference)


@pytest.mark.slow
def test_cantilever_tip_deflection_finer():
    """The same at 1.25 cm cells (8 through the depth): within 4 %."""
    measured, reference = cantilever_deflection(0.0125, 4.0)
    assert abs(measured / reference - 1) < 0.04, (measured, reference)


# -- damping -------------------------------------------------------------------------------

def vibrating_bar(damping: dict | None):
    """The strip clamped axially at its left end, stretched by an initial axial
    velocity: its first axial mode vibrates freely."""
    extra = {"boundary_conditions": [{"type": "velocity", "where": {"type": "box", "lower": [0, 0.3],
                                                                    "upper": [0.1, 0.7]}, "velocity": [0, None]}]}
    scene = bar(**extra, **({"damping": damping} if damping else {}))
    scene["bodies"][0]["initial_velocity"] = ["0.1 * sin(pi * (x - 0.1) / 2)", 0]
    return ExplicitMPM(load_scene(scene))


@pytest.mark.parametrize("damping", [{"type": "viscous", "coefficient": 20.0}, {"type": "local", "coefficient": 0.2}])
def test_damping_takes_out_the_energy_it_reports(damping):
    """Over 0.2 s (about 1.7 periods of the first axial mode) the damped bar loses
    most of its energy, and E(t) - E(0) equals the damping work to within the
    undamped bar's own drift (the scheme's dissipation) plus 1 % of the energy."""
    free, damped = vibrating_bar(None), vibrating_bar(damping)
    e0 = damped.energies().total
    run_until(free, 0.2)
    run_until(damped, 0.2)
    drift = abs(free.energies().total - e0)
    e = damped.energies()
    assert e.total < 0.5 * e0
    assert e.damping_work < 0
    assert abs(e.total - e0 - e.damping_work) <= drift + 0.01 * e0, (e.total, e0, e.damping_work, drift)


# -- errors --------------------------------------------------------------------------------

def test_a_load_box_without_particles_is_named():
    scene = load_scene(bar(loads=[{"type": "force", "body": "beam", "force": [0, 1],
                                   "where": {"type": "box", "lower": [0.0, 0.6], "upper": [0.1, 0.7]}}]))
    with pytest.raises(SceneError) as err:
        ExplicitMPM(scene)
    assert err.value.errors[0]["path"] == "loads[0].where"


@pytest.mark.parametrize("load,path", [
    ({"type": "force", "body": "nobody", "force": [0, 1]}, "loads[0].body"),
    ({"type": "force", "body": "beam", "force": [0, "1 +"]}, "loads[0].force[1]"),
    ({"type": "traction", "body": "beam", "traction": [0, 1, 2]}, "loads[0].traction"),
])
def test_bad_loads_are_named(load, path):
    load = {"where": {"type": "box", "lower": [1.0, 0.4], "upper": [1.2, 0.6]}, **load}
    with pytest.raises(SceneError) as err:
        load_scene(bar(loads=[load]))
    assert path in [e["path"] for e in err.value.errors], err.value.errors


def test_damping_with_several_processes_is_refused_until_ghost_nodes_count_once():
    scene = bar(damping={"type": "local", "coefficient": 0.1})
    scene["parallel"] = {"processes": 2}
    with pytest.raises(SceneError) as err:
        load_scene(scene)
    assert [e["path"] for e in err.value.errors] == ["damping"]
    assert "several processes" in err.value.errors[0]["message"]


def test_a_self_intersecting_polygon_is_named():
    scene = bar()
    scene["bodies"][0]["geometry"] = {"type": "polygon", "vertices": [[0.2, 0.4], [0.8, 0.6], [0.8, 0.4], [0.2, 0.6]]}
    with pytest.raises(SceneError) as err:
        load_scene(scene)
    assert err.value.errors[0]["path"] == "bodies[0].geometry.vertices"
    assert "edge 0" in err.value.errors[0]["message"] and "edge 2" in err.value.errors[0]["message"]


# -- polygons ------------------------------------------------------------------------------

POLYGONS = {
    "triangle": ([[0.1, 0.1], [0.9, 0.2], [0.3, 0.85]], 0.5 * abs(0.8 * 0.75 - 0.2 * 0.1)),
    "L-shape": ([[0.1, 0.1], [0.9, 0.1], [0.9, 0.4], [0.4, 0.4], [0.4, 0.9], [0.1, 0.9]], 0.8 * 0.3 + 0.3 * 0.5),
}


def polygon_mass(vertices, ppc: int) -> float:
    scene = load_scene({
        "dimension": 2, "grid": {"lower": [0, 0], "upper": [1, 1], "cell_size": 0.0437},
        "materials": {"m": {"model": "linear_elastic", "density": 1, "youngs_modulus": 1, "poisson_ratio": 0}},
        "bodies": [{"name": "p", "material": "m", "particles_per_cell": ppc,
                    "geometry": {"type": "polygon", "vertices": vertices[::-1] if ppc % 2 else vertices}}],
        "time": {"end": 1},
    })
    return float(seed(scene).volume.sum())


@pytest.mark.parametrize("name", POLYGONS)
def test_polygon_mass_converges_to_the_area(name):
    """Density 1, so the mass is the seeded area; cells of 0.0437 (not a divisor of the
    vertices' coordinates), either orientation. Every miscounted lattice cell (side
    s = h / ppc) touches the outline, so the error is at most perimeter x s / sqrt(2):
    O(s), first order in ppc. It is asserted for ppc = 2, 4, 8; the lattice's errors
    along an edge largely cancel, so the observed errors are far below the bound
    (measured 0.07 % -> 0.04 % for the triangle, see docs/benchmarks.md) and not
    monotone: no order beyond the bound is asserted."""
    vertices, area = POLYGONS[name]
    v = np.array(vertices)
    perimeter = float(np.sum(np.linalg.norm(v - np.roll(v, -1, axis=0), axis=1)))
    for ppc in (2, 4, 8):
        error = abs(polygon_mass(vertices, ppc) - area)
        assert error <= perimeter * (0.0437 / ppc) / math.sqrt(2), (ppc, error)
