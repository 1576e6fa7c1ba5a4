"""Contact with Coulomb friction ([R] 5.1, spec A.8): a block on an incline (a frictional
wall, a rigid body), bodies that slide past each other, the two disks (E2) with a field per
body, and the normals of a disk (E30).

The incline: gravity tilted by theta, the block on the face y = 0 (or on a rigid slab).
A rigid block slides with a = g (sin theta - mu cos theta) when mu < tan theta and stays
at rest otherwise. The block here is elastic (c = 45 m/s, a height crossed in 2 ms), so
its weight reaches the contact nodes with a vertical vibration of period 4 H / c ~ 9 ms;
the acceleration is fitted over 0.1 s < t < 0.3 s, twenty periods, which averages the
vibration's share of the normal force, and so of the friction, to about one part in forty
of its amplitude: the 1 % tolerance below.
"""
import math

import numpy as np
import pytest

from solver.scene_checks import load_scene
from solver.stepper import ExplicitMPM

G, H = 9.81, 0.02
RHO, E = 1000.0, 2e6


def incline(theta_deg, mu, support="wall", dim=2, end=0.3, **method):
    """A 0.2 x 0.1 block at rest on a frictional wall (the face y-) or on a rigid slab two
    cells thick, under gravity tilted by theta."""
    th = math.radians(theta_deg)
    extra = [0.0] * (dim - 2)
    floor = 2 * H if support == "rigid" else 0.0
    # 3D: the slab is wider than the block across the slope (z): at a rigid body's edge its
    # normal leans, and a block on that edge would be held along the lean
    bodies = [{"name": "block", "material": "rubber", "particles_per_cell": 2,
               "geometry": {"type": "box", "lower": [0.1, floor] + [0.02] * (dim - 2),
                            "upper": [0.3, floor + 0.1] + [0.08] * (dim - 2)}}]
    materials = {"rubber": {"model": "linear_elastic", "density": RHO, "youngs_modulus": E, "poisson_ratio": 0.3}}
    scene = {"version": 1, "name": "incline", "dimension": dim, "method": method,
             "grid": {"lower": [0.0, 0.0] + extra, "upper": [1.0, 0.2] + [0.1] * (dim - 2), "cell_size": H},
             "materials": materials, "bodies": bodies,
             "gravity": [G * math.sin(th), -G * math.cos(th)] + extra,
             "time": {"end": end}, "output": {"frames": 2}}
    if support == "wall":
        scene["boundary_conditions"] = [{"type": "wall", "face": "y-", "mode": "friction", "friction": mu}]
    else:   # two cells of grid around the slab: B-splines need nodes beyond a body
        scene["grid"]["lower"] = [-2 * H, -2 * H] + extra
        scene["grid"]["upper"][0] = 1.0 + 2 * H
        materials["steel"] = {"model": "rigid", "density": 7800.0}
        bodies.append({"name": "slope", "material": "steel", "particles_per_cell": 2,
                       "geometry": {"type": "box", "lower": [0.0, 0.0] + extra, "upper": [1.0, floor] + [0.1] * (dim - 2)}})
        scene["contact"] = {"model": "friction", "pairs": [{"bodies": ["block", "slope"], "friction": mu}]}
    return scene


def block_motion(scene, threads=1):
    """The block's centre-of-mass velocity along the slope against time, and the simulation."""
    scene = {**scene, "parallel": {"threads": threads}}
    sim = ExplicitMPM(load_scene(scene))
    p = sim.particles
    block = p.body == 0
    dt = sim.stable_time_step(0.5)
    t, v = [], []
    while sim.time < scene["time"]["end"]:
        sim.advance(dt)
        t.append(sim.time)
        v.append(float((p.mass[block] * p.v[block, 0]).sum() / p.mass[block].sum()))
    return np.array(t), np.array(v), sim


def fitted_acceleration(t, v):
    late = t > 0.1
    return np.polyfit(t[late], v[late], 1)[0]


def coulomb(theta_deg, mu):
    th = math.radians(theta_deg)
    return max(0.0, G * (math.sin(th) - mu * math.cos(th)))


@pytest.mark.parametrize("support", ["wall", "rigid"])
def test_block_slides_at_the_coulomb_acceleration(support):
    t, v, sim = block_motion(incline(30, 0.3, support))
    assert fitted_acceleration(t, v) == pytest.approx(coulomb(30, 0.3), rel=0.01)
    assert sim.work["friction_work"] < 0.0   # friction took energy out of the sliding


@pytest.mark.parametrize("support", ["wall", "rigid"])
def test_block_stays_at_rest_when_mu_exceeds_tan_theta(support):
    # mu = 0.7 > tan 30 = 0.577. PIC damps the block's elastic vibration; with FLIP it goes on,
    # and the contact nodes' load, released and restored with it, lets the block creep
    # (a ratchet, about 8 % of the sliding acceleration at mu = 0.3: docs/benchmarks.md).
    t, v, _ = block_motion(incline(30, 0.7, support, transfer="pic"))
    # at rest: the slope speed stays below what 1 % of the frictionless acceleration gives in 0.3 s
    assert np.max(np.abs(v)) < 0.01 * G * 0.5 * 0.3


def test_frictional_wall_in_tlmpm():
    # TLMPM's grid is the reference one: its face y = 0 holds the block's bottom wherever it went
    t, v, _ = block_motion(incline(30, 0.3, "wall", formulation="tlmpm"))
    assert fitted_acceleration(t, v) == pytest.approx(coulomb(30, 0.3), rel=0.01)


SCHEMES_AND_SHAPES = [(scheme, shape) for scheme in ("usl", "musl", "usf")
                      for shape in ("linear", "gimp", "quadratic_bspline", "cubic_bspline")
                      if (scheme, shape) != ("usl", "linear")]   # unstable here on a slip wall too (docs/benchmarks.md)


@pytest.mark.slow
@pytest.mark.parametrize("scheme,shape", SCHEMES_AND_SHAPES)
def test_rigid_slope_every_scheme_and_shape(scheme, shape):
    t, v, _ = block_motion(incline(30, 0.3, "rigid", scheme=scheme, shape_function=shape))
    assert fitted_acceleration(t, v) == pytest.approx(coulomb(30, 0.3), rel=0.01)


@pytest.mark.slow   # about 100 s, most of it compiling the 3D kernels for two threads
def test_block_slides_in_3d_with_two_threads():
    t, v, _ = block_motion(incline(30, 0.3, "rigid", dim=3, end=0.2), threads=2)
    late = t > 0.08
    assert np.polyfit(t[late], v[late], 1)[0] == pytest.approx(coulomb(30, 0.3), rel=0.02)


# -- bodies sliding past each other ----------------------------------------------------

def side_by_side(model, mu=0.0, push=0.0):
    """Two 0.2 x 0.2 blocks sharing the nodes of the plane x = 0.4; the left one moves along
    y at 1 m/s (and towards the right one at `push`)."""
    block = lambda name, x0, v: {"name": name, "material": "rubber", "particles_per_cell": 2,
                                 "geometry": {"type": "box", "lower": [x0, 0.3], "upper": [x0 + 0.2, 0.5]},
                                 "initial_velocity": v}
    scene = {"version": 1, "name": "sliding", "dimension": 2, "method": {"transfer": "pic"},
             "grid": {"lower": [0.0, 0.0], "upper": [1.0, 1.0], "cell_size": H},
             "materials": {"rubber": {"model": "linear_elastic", "density": RHO, "youngs_modulus": E,
                                      "poisson_ratio": 0.3}},
             "bodies": [block("left", 0.2, [push, 1.0]), block("right", 0.4, [0.0, 0.0])],
             "time": {"end": 0.05}, "output": {"frames": 2}}
    if model != "single_field":
        scene["contact"] = {"model": model, "friction": mu}
    return scene


def run_steps(scene, steps=100):
    sim = ExplicitMPM(load_scene(scene))
    dt = sim.stable_time_step(0.5)
    for _ in range(steps):
        sim.advance(dt)
    return sim


def body_momentum(sim, body):
    p = sim.particles
    sel = p.body == body
    return (p.mass[sel, None] * p.v[sel]).sum(axis=0)


def test_single_field_glues_where_frictionless_contact_slides():
    glued = run_steps(side_by_side("single_field"))
    free = run_steps(side_by_side("friction", mu=0.0))
    total = body_momentum(free, 0)[1] + body_momentum(free, 1)[1]
    # one field: the right block is dragged along (a good part of the momentum crosses)
    assert body_momentum(glued, 1)[1] > 0.05 * total
    # a field per body and no friction: nothing crosses a plane the bodies only slide along
    assert body_momentum(free, 1)[1] == pytest.approx(0.0, abs=1e-12 * total)
    assert body_momentum(free, 0)[1] == pytest.approx(total, rel=1e-12)


def test_friction_force_is_at_most_mu_times_the_normal_force():
    mu = 0.2
    sim = ExplicitMPM(load_scene(side_by_side("friction", mu=mu, push=0.5)))
    dt = sim.stable_time_step(0.5)
    normal = tangential = 0.0
    for _ in range(60):
        sim.advance(dt)
        series = sim.reactions()   # mean forces of this step
        n, t = series["contact_left_right_normal"], series["contact_left_right_tangential"]
        assert t <= mu * n * (1 + 1e-12)
        normal, tangential = normal + n, tangential + t
    assert normal > 0.0 and tangential > 0.0
    # the right block is dragged along y by the friction alone: at most mu times the normal impulse
    p_right = body_momentum(sim, 1)
    assert 0.0 < p_right[1] <= mu * normal * dt * (1 + 1e-9)
    # and the contact made no momentum: the left block lost what the right one gained
    total = body_momentum(sim, 0) + p_right
    p0 = RHO * 0.2 * 0.2 * np.array([0.5, 1.0])
    np.testing.assert_allclose(total, p0, rtol=1e-12)


# -- E2 with a field per body -----------------------------------------------------------

EXACT_CONTACT = (0.6 * math.sqrt(2) - 0.4) / (2 * math.sqrt(2) * 0.1)   # 1.5858 s: the gap over the closing speed

def two_disks(contact):
    import json
    from pathlib import Path
    scene = json.loads((Path(__file__).resolve().parents[2] / "examples" / "two_disks.json").read_text())
    scene["contact"] = contact
    return scene


@pytest.mark.slow
def test_two_disks_frictionless_contact_rebound_and_conserve_momentum():
    sim = ExplicitMPM(load_scene(two_disks({"model": "friction", "friction": 0.0})))
    e0 = sim.energies().kinetic
    p0 = body_momentum(sim, 0)
    for _ in range(3500):
        sim.advance(0.001)
    total = body_momentum(sim, 0) + body_momentum(sim, 1)
    assert np.abs(total).max() < 1e-12 * np.abs(p0).max()
    # the disks came apart: each moves back along the diagonal with most of its speed
    # (0.79 measured; the single field 0.94, docs/benchmarks.md)
    rebound = -body_momentum(sim, 0) @ p0 / (p0 @ p0)
    assert 0.7 < rebound < 1.0
    e = sim.energies()
    # the nodal correction is a perfectly inelastic impact of the contact nodes: it takes
    # energy (6 % measured), it never makes any; the rest is kinetic and the disks' vibration
    assert 0.9 * e0 < e.total <= e0 * (1 + 1e-9)


def test_two_disks_keep_their_energy_on_a_finer_grid():
    # The nodal correction's loss is that of the contact nodes' mass: at h = 0.05 (8 cells
    # across a disk) 5.9 %, at h = 0.025 1.2 %, at 0.0125 none (+0.2 %, FLIP 1's own error;
    # docs/benchmarks.md). At h = 0.025 the disks must rebound and keep the energy to 2 %.
    scene = two_disks({"model": "friction", "friction": 0.0})
    scene["grid"]["cell_size"] = 0.025
    sim = ExplicitMPM(load_scene(scene))
    e0 = sim.energies().kinetic
    p0 = body_momentum(sim, 0)
    for _ in range(7000):
        sim.advance(0.0005)
    assert np.abs(body_momentum(sim, 0) + body_momentum(sim, 1)).max() < 1e-12 * np.abs(p0).max()
    assert -body_momentum(sim, 0) @ p0 / (p0 @ p0) > 0.8   # apart, at 0.88 of the approach speed
    assert sim.energies().total == pytest.approx(e0, rel=0.02)


def head_on_blocks(scheme, shape="linear", transfer="flip"):
    """Two 0.1 x 0.1 blocks meeting face to face at 2 m/s (frictionless)."""
    block = lambda name, y0, v: {"name": name, "material": "rubber", "particles_per_cell": 2,
                                 "geometry": {"type": "box", "lower": [0.02, y0], "upper": [0.12, y0 + 0.1]},
                                 "initial_velocity": [0.0, v]}
    return {"version": 1, "name": "head-on", "dimension": 2,
            "method": {"scheme": scheme, "shape_function": shape, "transfer": transfer},
            "grid": {"lower": [-0.1, 0.0], "upper": [0.3, 0.5], "cell_size": H},
            "materials": {"rubber": {"model": "linear_elastic", "density": RHO, "youngs_modulus": E,
                                     "poisson_ratio": 0.3}},
            "bodies": [block("low", 0.1, 1.0), block("high", 0.26, -1.0)],
            "contact": {"model": "friction"}, "time": {"end": 0.1}, "output": {"frames": 2}}


@pytest.mark.parametrize("scheme,shape,transfer", [("musl", "linear", "flip"), ("usf", "linear", "flip"),
                                                   ("musl", "quadratic_bspline", "apic")])
def test_head_on_impact_makes_no_energy(scheme, shape, transfer):
    # contact only where the bodies' particles fill the nodes (the volume check): without it the
    # nodes one body barely reached made 11 % (MUSL), 120 % (USF) more energy than there was
    sim = ExplicitMPM(load_scene(head_on_blocks(scheme, shape, transfer)))
    e0 = sim.energies().total
    dt = sim.stable_time_step(0.5)
    while sim.time < 0.1:
        sim.advance(dt)
    assert sim.energies().total <= e0 * (1 + 1e-9)
    assert body_momentum(sim, 0)[1] < 0.0   # and they did bounce


def test_two_disks_meet_near_the_exact_time_and_conserve_momentum():
    # E2: the disks' surfaces meet at 1.5858 s; [R] sees the single field's contact at 1.3 s (a
    # cell early: shared nodes). With the volume check the bodies meet where their particles
    # fill a node: after the single field's time and not after the exact one (1.525 s measured).
    sim = ExplicitMPM(load_scene(two_disks({"model": "friction", "friction": 0.3})))
    for _ in range(1300):
        sim.advance(0.001)
    assert sim.reactions()["contact_disk1_disk2_normal"] == 0.0
    p0 = np.abs(body_momentum(sim, 0)).max()
    first = None
    while sim.time < 1.65:
        sim.advance(0.001)
        total = body_momentum(sim, 0) + body_momentum(sim, 1)
        assert np.abs(total).max() < 1e-12 * p0
        if first is None and sim.reactions()["contact_disk1_disk2_normal"] > 0.0:
            first = sim.time
    assert first is not None and 1.3 < first <= EXACT_CONTACT


# -- E30: normals of a disk ------------------------------------------------------------

def disk_normals(normals, h=0.05, radius=0.2):
    scene = {"version": 1, "name": "disk", "dimension": 2,
             "grid": {"lower": [-0.5, -0.5], "upper": [0.5, 0.5], "cell_size": h},
             "materials": {"rubber": {"model": "linear_elastic", "density": RHO, "youngs_modulus": E,
                                      "poisson_ratio": 0.3}},
             "bodies": [{"name": "disk", "material": "rubber", "particles_per_cell": 2,
                         "geometry": {"type": "sphere", "center": [0.0, 0.0], "radius": radius}}],
             "contact": {"model": "friction", "normals": normals},
             "time": {"end": 1.0}, "output": {"frames": 2}}
    sim = ExplicitMPM(load_scene(scene))
    sim.phases.weights()   # the contact hook's normals come with the weights (general backend)
    sim.phases.particles_to_grid(0.0)   # or with P2G (fused: solver/step/fused.py)
    contact = next(h for h in sim.hooks._hooks if hasattr(h, "gradient"))
    return sim.grid.node_positions(), contact.presence, contact.gradient


def test_e30_normals_point_out_of_the_disk_and_the_two_definitions_agree():
    x, presence, by_mass = disk_normals("mass_gradient")
    _, _, by_density = disk_normals("density_gradient")
    r = np.linalg.norm(x, axis=1)
    # E30's boundary nodes: those of the non-empty cells the circle cuts (within a cell diagonal of
    # it), less the few inside the particles' staircase where the particles around a node balance
    # and the mass gradient vanishes (it is round-off there: no normal, and no contact either)
    scale = np.abs(by_mass).max()
    boundary = (np.abs(r - 0.2) < 0.05 * math.sqrt(2)) & (presence > 0) & (np.abs(by_mass).max(axis=1) > 1e-9 * scale)
    unit = lambda g: g / np.linalg.norm(g, axis=1)[:, None]
    radial = x[boundary] / r[boundary, None]
    angle = lambda a, b: np.degrees(np.arccos(np.clip(np.sum(a * b, axis=1), -1, 1)))
    # The particles fill the cells inside a staircase of the circle (2 x 2 per cell). The mass
    # gradient with the linear hat follows the staircase: where a single step's corner contributes,
    # the normal lies along the step's diagonal, atan(1/2) = 26.6 degrees from the radius at most.
    # The density gradient spreads each particle over three cells (the quadratic B-spline) and
    # smooths the steps out: measured 4.1 degrees at most, asserted below 5.
    to_radius_mass = angle(unit(by_mass[boundary]), radial)
    to_radius_density = angle(unit(by_density[boundary]), radial)
    assert to_radius_mass.max() <= math.degrees(math.atan(0.5)) + 1e-9
    assert to_radius_density.max() < 5.0
    assert to_radius_mass.mean() < 10 and to_radius_density.mean() < 3
    # [R] Remark 32 finds the two "identical"; here they differ by the mass gradient's staircase:
    # 5.5 degrees on average over the 48 nodes (docs/benchmarks.md), asserted below 6
    between = angle(unit(by_mass[boundary]), unit(by_density[boundary]))
    assert between.mean() < 6.0


# -- a rolling cylinder ------------------------------------------------------------------

def rolling_disk(mu, h, end=0.3):
    """A disk of radius 0.1 on the frictional face y = 0 of the incline (a cylinder in plane strain)."""
    scene = incline(30, mu, "wall", end=end)
    scene["grid"]["cell_size"] = h
    scene["grid"]["upper"][1] = 0.4
    scene["bodies"][0]["geometry"] = {"type": "sphere", "center": [0.2, 0.1], "radius": 0.1}
    return scene


def test_frictionless_disk_accelerates_at_g_sin_theta():
    t, v, _ = block_motion(rolling_disk(0.0, 0.02))
    assert fitted_acceleration(t, v) == pytest.approx(G * 0.5, rel=1e-6)   # g sin theta, nothing resists


def test_rolling_disk_rolls_at_two_thirds_g_sin_theta():
    # mu = 0.5 > tan(30) / 3: rolling without slipping, a = (2/3) g sin theta for a uniform
    # cylinder. The contact is resolved at the nodes: the friction acts a cell's distance off
    # the true contact point at worst, which moves the lever arm R by up to h, and a =
    # g sin theta / (1 + I / (m R^2)) by (2/3) h / R. Measured: -50 %, -10 %, +3.6 %, +0.8 %
    # at 5, 10, 20, 40 cells per radius (docs/benchmarks.md); asserted within h / R at 20.
    exact = 2.0 / 3.0 * G * 0.5
    h = 0.005
    assert fitted_acceleration(*block_motion(rolling_disk(0.5, h))[:2]) == pytest.approx(exact, rel=h / 0.1)


@pytest.mark.slow
def test_rolling_disk_converges_to_two_thirds_g_sin_theta():
    # mu = 0.5 > tan(30) / 3: rolling without slipping, a = (2/3) g sin theta for a uniform cylinder.
    # The contact is resolved at the grid's nodes, and the rolling disk's contact patch moves from
    # node to node: at 5 cells per radius it rolls at half the rate, at 10 cells at 0.9 of it.
    # Asserted: between the sliding and the rolling rates, and an error that more than halves
    # with the cell (first order or better).
    exact = 2.0 / 3.0 * G * 0.5
    coarse = fitted_acceleration(*block_motion(rolling_disk(0.5, 0.02))[:2])
    fine = fitted_acceleration(*block_motion(rolling_disk(0.5, 0.01))[:2])
    assert coulomb(30, 0.5) < coarse < fine < exact
    assert exact - fine < 0.5 * (exact - coarse)
