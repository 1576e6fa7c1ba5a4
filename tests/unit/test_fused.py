"""The fused kernels (solver/fused.py) give the general kernels' answer.

Both compute the same weights from the same formulas; they differ only in the
order of some additions (the force on a node, the APIC momentum, D_p = h^2/4
taken exactly for quadratic B-splines instead of summed): round-off, about 1e-16
relative per step, which a stable elastic run does not amplify much. After 60
steps of two bodies colliding under gravity on a slip floor, positions,
velocities, F and (hypoelastic, so no cancellation in sigma(F)) stresses agree
to 1e-12 relative, the bound the process-equivalence tests use too.
"""
from __future__ import annotations

import copy
from dataclasses import replace
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest
from numba import njit

from solver import fused, fused_template, generated, near_one_log, shape
from solver.scene_checks import load_scene
from solver.step.fused import FusedPhases
from solver.stepper import ExplicitMPM, Instability

TOLERANCE = 1e-12
STEPS = 60


def slow(*values):
    """A case left out of the default run (`-m slow` runs it): a 3D variant more of a feature
    that the default run checks in 3D once already. Each 3D kernel variant compiles for 40-70 s
    on one core, which is most of a cold run."""
    return pytest.param(*values, marks=pytest.mark.slow)


# `threads` in a case: the tests that compare two kernels bit for bit do it on two threads in one
# case each, where both parallel forms must sum the threads' rows in the same order; their other
# cases run on one thread, in the serial twins (solver/jit.py), which compile in about a third of
# the time (a parallel form in 2D takes 10-25 s to compile on this 2-core machine, in 3D 25-35 s).


@pytest.fixture
def reproducible(monkeypatch):
    """Fused kernels compiled without FMA contraction (MPM_FMA=0; by default they contract:
    solver/fused_template.py CONTRACT), where a test holds them to the bits of kernels compiled
    without it."""
    monkeypatch.setenv(fused_template.FMA, "0")

SCENE_2D = {
    "name": "fused-2d", "dimension": 2,
    "grid": {"lower": [0.0, 0.0], "upper": [1.0, 0.5], "cell_size": 0.04},
    "materials": {"m": {"model": "linear_elastic", "density": 1000, "youngs_modulus": 1e4, "poisson_ratio": 0.3}},
    "bodies": [
        {"name": "left", "material": "m", "particles_per_cell": 2, "initial_velocity": [1.0, "0.3 * sin(7 * y)"],
         "geometry": {"type": "sphere", "center": [0.36, 0.2], "radius": 0.12}},
        {"name": "right", "material": "m", "particles_per_cell": 2, "initial_velocity": [-1.0, 0.0],
         "geometry": {"type": "box", "lower": [0.49, 0.08], "upper": [0.73, 0.32]}},
    ],
    "boundary_conditions": [{"type": "wall", "face": "y-", "mode": "slip"}],
    "gravity": [0.0, -9.8],
    "time": {"end": 1.0, "dt": 2e-4},
}
SCENE_3D = {
    **copy.deepcopy(SCENE_2D), "name": "fused-3d", "dimension": 3,
    "grid": {"lower": [0.0, 0.0, 0.0], "upper": [1.0, 0.4, 0.4], "cell_size": 0.08},
    "bodies": [
        {"name": "left", "material": "m", "particles_per_cell": 2, "initial_velocity": [1.0, 0.0, "0.3 * sin(7 * y)"],
         "geometry": {"type": "sphere", "center": [0.36, 0.2, 0.2], "radius": 0.12}},
        {"name": "right", "material": "m", "particles_per_cell": 2, "initial_velocity": [-1.0, 0.0, 0.0],
         "geometry": {"type": "box", "lower": [0.49, 0.1, 0.1], "upper": [0.73, 0.3, 0.3]}},
    ],
    "boundary_conditions": [{"type": "wall", "face": "z-", "mode": "slip"}],
    "gravity": [0.0, 0.0, -9.8],
}
METHODS = {
    "musl-linear-flip": {"scheme": "musl", "shape_function": "linear", "transfer": "flip", "flip_ratio": 0.99},
    "usl-linear-pic": {"scheme": "usl", "shape_function": "linear", "transfer": "pic"},
    "musl-quadratic-apic": {"scheme": "musl", "shape_function": "quadratic_bspline", "transfer": "apic"},
    "usl-quadratic-flip": {"scheme": "usl", "shape_function": "quadratic_bspline", "transfer": "flip",
                           "flip_ratio": 0.95},
    "usl-quadratic-mls": {"scheme": "usl", "shape_function": "quadratic_bspline", "transfer": "mls"},
    "musl-quadratic-mls": {"scheme": "musl", "shape_function": "quadratic_bspline", "transfer": "mls"},
}


def relative_difference(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


@pytest.mark.parametrize("method,dimension", [
    *((method, 2) for method in METHODS),
    ("musl-quadratic-apic", 3), ("usl-quadratic-mls", 3),
    *(slow(method, 3) for method in METHODS if method not in ("musl-quadratic-apic", "usl-quadratic-mls"))])
def test_fused_step_gives_the_general_step(dimension, method):
    scene = load_scene({**(SCENE_2D if dimension == 2 else SCENE_3D), "method": METHODS[method]})
    fast, general = ExplicitMPM(scene), ExplicitMPM(scene)
    general.use_general_kernels()
    assert fast.fused and not general.fused
    for _ in range(STEPS):
        fast.advance(2e-4)
        general.advance(2e-4)
    a, b = fast.particles, general.particles
    assert np.max(np.abs(b.stress[:, 0, 0])) > 300.0   # the bodies did collide (sigma_xx of order rho c v)
    for name in ("x", "v", "F", "stress", "volume"):
        assert relative_difference(getattr(a, name), getattr(b, name)) <= TOLERANCE, name
    if METHODS[method]["transfer"] in ("apic", "mls"):
        assert relative_difference(a.extra["affine"], b.extra["affine"]) <= TOLERANCE
    assert fast.work["boundary_work"] == pytest.approx(general.work["boundary_work"], rel=1e-9, abs=1e-12)


@pytest.mark.parametrize("change,expected", [
    ({}, True),
    ({"method": {"shape_function": "gimp"}}, False),
    ({"method": {"scheme": "usf"}}, False),
    ({"method": {"formulation": "tlmpm"}}, False),
    ({"axisymmetric": True}, False),
])
def test_fused_kernels_take_the_scenes_they_implement(change, expected):
    assert fused.supports(load_scene({**SCENE_2D, **change})) is expected


def test_fused_apic_needs_a_constant_d_p_from_the_shape_function(monkeypatch):
    scene = load_scene({**SCENE_2D, "method": METHODS["musl-quadratic-apic"]})
    assert fused.supports(scene)
    monkeypatch.setitem(shape.REGISTRY, "quadratic_bspline", replace(shape.REGISTRY["quadratic_bspline"], apic_d=None))
    assert not fused.supports(scene)
    assert not ExplicitMPM(scene).fused


def test_the_generated_kernels_are_rewritten_only_when_the_template_changes(tmp_path, monkeypatch):
    monkeypatch.setattr(generated, "_folders", lambda kind: [tmp_path])
    path = fused_template.write(3)
    assert path.parent == tmp_path and path.read_text() == fused_template.source(3)
    stamp = path.stat().st_mtime_ns
    assert fused_template.write(3) == path and path.stat().st_mtime_ns == stamp   # numba's cache stays valid
    path.write_text("# an older template's output\n")
    fused_template.write(3)
    assert path.read_text() == fused_template.source(3)


def test_a_particle_leaving_the_grid_is_named_by_the_fused_step():
    scene = copy.deepcopy(SCENE_2D)
    scene["bodies"][0]["initial_velocity"] = [-2000.0, 0.0]
    scene["time"] = {**scene["time"], "allow_unstable_dt": True}   # meant: the particles fly off the grid
    sim = ExplicitMPM(load_scene(scene))
    assert sim.fused
    with pytest.raises(Exception, match="position of particle"):
        for _ in range(5):
            sim.advance(2e-4)


QUADRATIC_APIC = {"scheme": "usl", "shape_function": "quadratic_bspline", "transfer": "apic"}


@pytest.mark.parametrize("method,extra,dimension,folds", [
    (METHODS["usl-quadratic-mls"], {}, 2, True),
    (METHODS["musl-quadratic-mls"], {}, 2, True),
    (METHODS["musl-quadratic-apic"], {}, 2, True),
    (QUADRATIC_APIC, {}, 2, True),
    (QUADRATIC_APIC, {}, 3, True),
    (METHODS["usl-quadratic-flip"], {}, 2, False),                      # the FLIP blend reads v_I^t
    (METHODS["usl-quadratic-mls"], {"damping": {"type": "viscous", "coefficient": 5.0}}, 2, False),   # damping reads f_I
    (QUADRATIC_APIC, {"damping": {"type": "viscous", "coefficient": 5.0}}, 2, False),
])
def test_fused_step_folds_the_force_into_the_momentum_only_where_nothing_reads_it(method, extra, dimension, folds):
    """The folded P2G (dt f_I in (mv)_I, solver/step/fused.py) gives the unfolded step to round-off
    (1e-12 relative after 60 steps, as the fused kernels against the general ones); it is chosen for
    MLS, and APIC with quadratic B-splines, without a FLIP blend or a hook on f_I or v_I^t only."""
    scene = load_scene({**(SCENE_2D if dimension == 2 else SCENE_3D), **extra, "method": method})
    folded, unfolded = ExplicitMPM(scene), ExplicitMPM(scene)
    assert folded.phases.plan.fold is folds
    unfolded.phases.replan(without=("fold",))
    for _ in range(STEPS):
        folded.advance(2e-4)
        unfolded.advance(2e-4)
    a, b = folded.particles, unfolded.particles
    assert np.max(np.abs(b.stress[:, 0, 0])) > 300.0   # the bodies did collide
    for name in ("x", "v", "F", "stress"):
        assert relative_difference(getattr(a, name), getattr(b, name)) <= TOLERANCE, name
    if method["transfer"] != "flip":
        assert relative_difference(a.extra["affine"], b.extra["affine"]) <= TOLERANCE
    assert folded.work["boundary_work"] == pytest.approx(unfolded.work["boundary_work"], rel=1e-9, abs=1e-12)


def test_a_hook_added_after_placement_is_in_the_plan():
    """The plan is chosen when the particles are placed and again when a hook is added: a hook that
    reads f_I (after_forces) unfolds the force, and a choice left out stays out when the particles
    are placed again."""
    sim = ExplicitMPM(load_scene(neo_hookean_mls(SCENE_2D)))
    assert sim.phases.plan.fold and sim.phases.plan.p2g == "p2g_mls_lanes"

    class ReadsTheForce:
        def after_forces(self, sim):
            pass
    sim.add_hook(ReadsTheForce())
    assert not sim.phases.plan.fold and sim.phases.plan.p2g == "p2g"
    other = ExplicitMPM(load_scene(neo_hookean_mls(SCENE_2D)))
    other.phases.replan(without=("lanes",))
    other.place()
    assert other.phases.plan.p2g == "p2g_mls"


def _lone_particle_step(inside: float, fold: bool) -> tuple[np.ndarray, np.ndarray, float]:
    """One USL APIC step of a lone stressed particle `inside` cells within the reach of the
    node below it along x (its quadratic weight there is inside^2 / 2): F_p, v_p and the node's
    mass over the cut-off."""
    h = 0.1
    scene = load_scene({
        "name": "fringe", "dimension": 2, "grid": {"lower": [0.0, 0.0], "upper": [1.0, 1.0], "cell_size": h},
        "materials": {"m": {"model": "linear_elastic", "density": 1000, "youngs_modulus": 1e6, "poisson_ratio": 0.3}},
        "bodies": [{"name": "b", "material": "m", "particles_per_cell": 1,
                    "geometry": {"type": "box", "lower": [0.5, 0.5], "upper": [0.6, 0.6]}}],
        "method": QUADRATIC_APIC, "time": {"end": 1.0, "dt": 1e-4}})
    sim = ExplicitMPM(scene)
    if not fold:
        sim.phases.replan(without=("fold",))
    assert sim.phases.plan.fold is fold and sim.particles.count == 1
    p = sim.particles
    p.x[0] = [(5.5 - inside) * h, 0.55]
    p.stress[0] = [[1e4, 2e3, 0.0], [2e3, -5e3, 0.0], [0.0, 0.0, 1.5e3]]
    sim.advance(1e-4)
    return p.F[0].copy(), p.v[0].copy(), 0.5 * inside**2 * p.mass[0] / sim.mass_cutoff


def test_folded_apic_step_has_no_jump_where_the_mass_cut_off_drops_a_node():
    """Unfolded, a node whose mass falls below the cut-off loses dt f_I / m_I. With quadratic
    B-splines that term gives the particle's L_p a finite share (grad w ~ d / h against
    f_I / m_I ~ 1 / d at d cells inside the node's reach), so the unfolded F_p jumps where the
    cut-off bites, and the dropped force breaks momentum balance. The folded step keeps the term:
    F_p at d = 1e-6 (node below the cut-off) is F_p at d = 1e-4 (above it) to O(d) relative,
    and the lone particle's momentum stays zero to round-off."""
    above, below = 1e-4, 1e-6
    F_fold_above, _, mass_above = _lone_particle_step(above, True)
    F_plain_above, _, _ = _lone_particle_step(above, False)
    F_fold_below, v_fold_below, mass_below = _lone_particle_step(below, True)
    F_plain_below, v_plain_below, _ = _lone_particle_step(below, False)
    assert mass_above > 1.0 > mass_below
    increment = np.abs(F_fold_above - np.eye(2)).max()
    assert np.abs(F_plain_above - F_fold_above).max() <= 1e-9 * increment   # both keep the node
    assert np.abs(F_fold_below - F_fold_above).max() <= 10 * above * increment
    assert np.abs(F_plain_below - F_fold_above).max() >= 0.1 * increment     # the cut-off's jump
    assert np.abs(v_fold_below).max() <= 1e-15 and np.abs(v_plain_below).max() >= 1e-9

# -- heat conduction carried by the fused kernels (MUSL) ------------------------------

HEAT = {"thermal_conductivity": 2.0e5, "specific_heat": 500.0}


def conducting(dimension: int, method: str, threads: int) -> dict:
    """The two bodies of SCENE_2D/3D, the left a box that conducts, held at 400 K near x = 0,
    the right without thermal keys (it takes no part in conduction)."""
    scene = copy.deepcopy(SCENE_2D if dimension == 2 else SCENE_3D)
    scene["materials"] = {"m": {**scene["materials"]["m"], **HEAT}, "cold": scene["materials"]["m"]}
    left, right = scene["bodies"]
    left["initial_temperature"] = 300.0
    left["geometry"] = {"type": "box", "lower": [0.05] + right["geometry"]["lower"][1:],
                        "upper": [0.45] + right["geometry"]["upper"][1:]}
    right["material"] = "cold"
    upper = scene["grid"]["upper"]
    scene["boundary_conditions"].append({"type": "temperature", "temperature": 400.0,
                                         "where": {"type": "box", "lower": [0.0] * dimension,
                                                   "upper": [0.13] + upper[1:]}})
    return {**scene, "method": METHODS[method], "parallel": {"threads": threads},
            "time": {**scene["time"], "dt": 1e-4}}


def test_the_kernels_fuse_multiply_and_add_where_the_environment_asks_for_it(monkeypatch):
    monkeypatch.setenv(fused_template.FMA, "0")
    assert "fastmath" not in fused_template.source(3)
    decorator = "@njit(parallel=True, cache=True, fastmath={'contract'})".replace("'", '"')
    monkeypatch.delenv(fused_template.FMA, raising=False)   # the default
    assert fused_template.source(3).count(decorator) == 4   # p2g, g2p, p2g_lanes and g2p_lanes
    monkeypatch.setenv(fused_template.FMA, "1")
    # p2g, g2p, p2g_mls, p2g_mls_lanes, g2p_mls and g2p_kinematics
    assert fused_template.source(2).count(decorator) == 6
    monkeypatch.setenv(fused_template.FMA, "yes")
    with pytest.raises(ValueError, match="MPM_FMA='yes': must be 0"):
        fused_template.source(2)


@njit(fastmath={"contract"})
def _middle_weight_through_axis(x, inv_h, cells):
    """A contracted caller of `_axis`, as the fused kernels are (compiled here, never cached)."""
    return fused._axis(3, x, 0.0, inv_h, cells)[3][1]


def _middle_weight(x, inv_h, cells):
    """`_axis`'s middle quadratic B-spline weight (lower = 0) in plain Python, which rounds
    t*t before the subtraction."""
    s = x * inv_h
    t = s - min(max(int(s - 0.5), 0), cells - 2) - 1.0
    return 0.75 - t * t


# the same function compiled with contraction: 0.75 - t*t becomes one fused operation
_middle_weight_contracted = njit(fastmath={"contract"})(_middle_weight)


def test_the_contracted_kernels_leave_the_weights_they_call_uncontracted():
    """numba compiles a called function once per signature, with the fastmath of its first
    caller (a callee inherits it), and caches it so: a function the contracted kernels call
    first would reach the reproducible ones contracted. `_axis` (the quadratic B-spline weights,
    the kernels' one callee with a product to contract: 0.75 - t*t) says fastmath=False, so a
    contracted first caller still gets the product rounded before the subtraction."""
    cells, inv_h = 64, 64.0 / 0.9
    xs = np.random.default_rng(3).uniform(0.05, 0.85, 400)
    separately = [_middle_weight(x, inv_h, cells) for x in xs]
    contracted = [_middle_weight_contracted(x, inv_h, cells) for x in xs]
    if contracted == separately:
        pytest.skip("this CPU has no fused multiply-add: nothing is contracted")
    assert [_middle_weight_through_axis(x, inv_h, cells) for x in xs] == separately


@pytest.mark.parametrize("dimension,method,threads", [
    (2, "musl-linear-flip", 1), (2, "musl-linear-flip", 2), (3, "musl-linear-flip", 1),
    (2, "musl-quadratic-mls", 1), slow(3, "musl-quadratic-apic", 1)])
def test_fused_conduction_gives_the_separate_thermal_passes(dimension, method, threads, reproducible):
    """The thermal kernels do thermal_kernels.py's sums in the same order on the same weights
    (compiled without FMA contraction, `reproducible`, as the separate passes are).
    In 2D the weights are the same bits, so after one step from the same state T_p and q_p
    are too; in 3D the fused weight wx (wy wz) and the stored ((wx wy) wz) differ in the last
    bit, and MLS's gradient takes D_p = h^2/4 exactly where the general one sums it. Over 60 steps the mechanics' round-off (see the module docstring) reaches the
    temperatures through x_p and V_p: 1e-12 relative, as for the mechanics."""
    scene = load_scene(conducting(dimension, method, threads))
    fast, general = ExplicitMPM(scene), ExplicitMPM(scene, general=True)
    assert fast.fused and not general.fused
    a, b = fast.particles.extra, general.particles.extra
    cold = general.particles.body == 1
    start = b["temperature"][cold].copy()
    fast.advance(1e-4)
    general.advance(1e-4)
    for name in ("temperature", "heat_flux"):
        if dimension == 2 and METHODS[method]["transfer"] != "mls":
            assert np.array_equal(a[name], b[name]), name
        assert relative_difference(a[name], b[name]) <= TOLERANCE, name
    for _ in range(STEPS - 1):
        fast.advance(1e-4)
        general.advance(1e-4)
    T = b["temperature"]
    assert np.ptp(T[general.particles.body == 0]) > 10.0   # the heat did spread into the body
    assert np.array_equal(T[cold], start) and np.array_equal(a["temperature"][fast.particles.body == 1], start)
    for name in ("temperature", "heat_flux"):
        assert relative_difference(a[name], b[name]) <= TOLERANCE, name
    assert relative_difference(fast.conduction.grid_temperature(), general.conduction.grid_temperature()) <= TOLERANCE
    assert relative_difference(fast.particles.x, general.particles.x) <= TOLERANCE


def test_conduction_with_usl_keeps_the_general_backend():
    """USL's one fused G2P pass moves x_p before the flux could be gathered at x_p^t."""
    scene = conducting(2, "usl-linear-pic", 1)
    assert not fused.supports(load_scene(scene))
    assert fused.supports(load_scene({**scene, "method": METHODS["musl-linear-flip"]}))


def test_conduction_with_a_frictional_wall_keeps_the_general_backend():
    """The wall's frictional heat goes into T~_I^{t+dt} after the grid update, before the
    particles take it; the fused REMAP pass would take T~ first (solver/thermal.py)."""
    scene = conducting(2, "musl-linear-flip", 1)
    wall = {"type": "wall", "face": "y+", "mode": "friction", "friction": 0.3}
    assert not fused.supports(load_scene({**scene, "boundary_conditions": scene["boundary_conditions"] + [wall]}))
    assert fused.supports(load_scene(scene))


def test_a_scene_without_heat_loads_the_kernels_of_a_template_without_heat():
    """Conduction adds to the generated text only where the scene conducts."""
    for dimension in (2, 3):
        plain, thermal = fused_template.source(dimension), fused_template.source(dimension, thermal=True)
        assert "capacity" not in plain and "heat" not in plain
        assert "heat_flux" in thermal
    loaded = Path(ExplicitMPM(load_scene(SCENE_2D)).phases._kernels.__file__).read_text()
    assert "capacity" not in loaded and "heat" not in loaded


# -- contact with a velocity field per body -----------------------------------------

CONTACT = {"model": "friction", "friction": 0.3}


def in_contact(dimension: int, method: str, threads: int) -> dict:
    """The two bodies of SCENE_2D/3D, each in a field of its own, meeting from the first steps."""
    return {**(SCENE_2D if dimension == 2 else SCENE_3D), "method": METHODS[method], "contact": CONTACT,
            "parallel": {"threads": threads}}


@pytest.mark.parametrize("dimension,method,threads", [
    (2, "musl-linear-flip", 1), (2, "usl-linear-pic", 2), (2, "musl-quadratic-apic", 1), (2, "usl-quadratic-mls", 1),
    slow(3, "musl-linear-flip", 2), slow(3, "usl-quadratic-flip", 1), (3, "musl-quadratic-apic", 1),
    slow(3, "musl-quadratic-mls", 2)])
def test_fused_contact_gives_the_general_step(dimension, method, threads):
    """The fused kernels shift each particle's nodes into its body's field and scatter the
    contact's presence and normals in P2G, as the hook's pass over the stored stencil does:
    the same sums in the same order (2D: the same bits but for MLS's D_p; 3D: the weights'
    round-off of the module docstring), so the states and the pair forces agree to 1e-12."""
    scene = load_scene(in_contact(dimension, method, threads))
    fast, general = ExplicitMPM(scene), ExplicitMPM(scene, general=True)
    assert fast.fused and not general.fused
    forces = []
    for step in range(STEPS):
        fast.advance(2e-4)
        general.advance(2e-4)
        if step % 10 == 9:
            forces.append((fast.hooks.series(), general.hooks.series()))
    a, b = fast.particles, general.particles
    assert np.max(np.abs(b.stress[:, 0, 0])) > 300.0   # the bodies did collide
    for name in ("x", "v", "F", "stress", "volume"):
        assert relative_difference(getattr(a, name), getattr(b, name)) <= TOLERANCE, name
    normal = [series["contact_left_right_normal"] for _, series in forces]
    assert max(normal) > 0.0   # the contact acted
    for fast_series, general_series in forces:
        assert fast_series.keys() == general_series.keys()
        for key, value in general_series.items():
            assert fast_series[key] == pytest.approx(value, rel=TOLERANCE, abs=TOLERANCE * max(normal)), key


@pytest.mark.parametrize("contact,expected", [
    (CONTACT, True),
    ({**CONTACT, "normals": "density_gradient"}, False),   # the cells' densities are a pass of their own
    ({"model": "single_field"}, True),
])
def test_fused_contact_takes_the_mass_gradient_normals(contact, expected):
    assert fused.supports(load_scene({**SCENE_2D, "contact": contact})) is expected


def test_contact_with_conduction_keeps_the_general_backend():
    """The fields' heat exchange and the frictional heat enter T~_I^{t+dt} before the particles
    take it, as a frictional wall's (solver/thermal.py)."""
    scene = conducting(2, "musl-linear-flip", 1)
    assert not fused.supports(load_scene({**scene, "contact": CONTACT}))


def test_a_scene_without_contact_loads_the_kernels_of_a_template_without_contact():
    for dimension in (2, 3):
        plain, fields = fused_template.source(dimension), fused_template.source(dimension, contact=True)
        assert "shift" not in plain and "presence" not in plain
        assert "field_of_body" in fields and "presence" in fields
    sim = ExplicitMPM(load_scene({**SCENE_2D, "contact": CONTACT}))
    assert "field_of_body" in Path(sim.phases._kernels.__file__).read_text() and sim.stencil is None


# -- the stress formed inside P2G (a material whose stress is a function of what P2G reads) -------

NEO_HOOKEAN = {"model": "neo_hookean", "density": 1000, "youngs_modulus": 1e4, "poisson_ratio": 0.3}
# the Tait fluid with pow(), a viscous deviator and a tension cut-off; and mpm88's (gamma = 1)
FLUID = {"model": "fluid", "density": 1000, "bulk_modulus": 1e4, "gamma": 7.0, "viscosity": 5.0,
         "tension_cutoff": 50.0}
LINEAR_FLUID = {"model": "fluid", "density": 1000, "bulk_modulus": 1e4, "gamma": 1.0}
# The 2D MLS cases on two threads all take FLUID without contraction (MPM_FMA=0, the suite's
# default): the parallel forms of one module, compiled once (10-20 s each on this machine) and
# loaded by the others; contraction is covered on one thread.


def stepped_with_and_without(scene, switch: str) -> tuple:
    """Two simulations of the scene after STEPS steps: the fused plan with `switch` (a choice the plan
    makes for the scene, solver/step/fused.py CHOICES) and the plan without it."""
    on, off = ExplicitMPM(scene), ExplicitMPM(scene)
    assert on.phases.plan.makes(switch)
    off.phases.replan(without=(switch,))
    for _ in range(STEPS):
        on.advance(2e-4)
        off.advance(2e-4)
    return on, off


@pytest.mark.parametrize("material,dimension,method,threads", [
    (NEO_HOOKEAN, 2, "usl-quadratic-mls", 1), slow(NEO_HOOKEAN, 3, "usl-quadratic-mls", 2),
    (NEO_HOOKEAN, 2, "musl-quadratic-apic", 1), (NEO_HOOKEAN, 2, "usl-linear-pic", 1),
    (FLUID, 2, "usl-quadratic-mls", 2), (FLUID, 3, "usl-quadratic-mls", 1), (FLUID, 2, "musl-quadratic-apic", 1),
    (LINEAR_FLUID, 2, "usl-quadratic-mls", 1), (LINEAR_FLUID, 2, "usl-linear-pic", 1)])
def test_the_stress_formed_in_p2g_gives_the_stress_pass_bit_for_bit(material, dimension, method, threads,
                                                                    reproducible):
    """A neo-Hookean or fluid scene's fused P2G forms sigma_p (from F_p; from L_p and V_p / V0_p)
    and the stress pass is put off (Particles.defer); with MLS's USL gather L_p (= C_p) is not
    written either. The same operations in the same order (and, `reproducible`, no multiply and
    add fused where the material's own pass has none): the state is that of the step that stores
    both, to the bit."""
    scene = copy.deepcopy(SCENE_2D if dimension == 2 else SCENE_3D)
    scene["materials"]["m"] = material
    scene = load_scene({**scene, "method": METHODS[method], "parallel": {"threads": threads}})
    formed, stored = stepped_with_and_without(scene, "forms_stress")
    a, b = formed.particles, stored.particles
    assert a.pending("stress") and not b.pending("stress")
    assert a.pending("L") is (method == "usl-quadratic-mls") and not b.pending("L")
    if material["model"] == "fluid":   # its sound speed comes with the update: reading it runs the update
        assert formed.wave_speed == stored.wave_speed and not a.pending("stress")
    for name in ("x", "v", "F", "L", "stress", "volume"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert not a.pending("stress") and not a.pending("L")


@pytest.mark.parametrize("extra", [
    {"materials": {"m": NEO_HOOKEAN, "n": SCENE_2D["materials"]["m"]}},          # two materials
    {"materials": {"m": SCENE_2D["materials"]["m"]}},                           # a rate (hypoelastic) model
    {"method": {**METHODS["usl-quadratic-mls"], "fbar": True}},                 # a hook after the stress update
    {"materials": {"m": FLUID}, "time": {"end": 1.0, "cfl": 0.3}},              # a wave speed the CFL step reads
])
def test_the_stress_pass_runs_where_p2g_cannot_form_the_stress(extra):
    scene = copy.deepcopy(SCENE_2D)
    scene["materials"] = {"m": NEO_HOOKEAN}
    scene["method"] = METHODS["usl-quadratic-mls"]
    scene.update(copy.deepcopy(extra))
    if "n" in scene["materials"]:
        scene["bodies"][1]["material"] = "n"
    sim = ExplicitMPM(load_scene(scene))
    sim.advance(2e-4)
    assert not sim.phases.forms_stress()
    assert not sim.particles.pending("stress") and not sim.particles.pending("L")


# -- the stress updated inside G2P (a rate model whose update is a function of L_p) ---------------

@pytest.mark.parametrize("dimension,method,threads", [
    (3, "musl-linear-flip", 1), slow(3, "musl-linear-flip", 2), (2, "usl-quadratic-apic", 1),
    slow(3, "usl-quadratic-mls", 1), (2, "usl-linear-pic", 2), (2, "musl-quadratic-mls", 1)])
def test_the_stress_updated_in_g2p_gives_the_stress_pass_bit_for_bit(dimension, method, threads, reproducible):
    """A linear elastic scene's fused G2P (USL's pass, MUSL's kinematics pass) updates sigma_p
    from the L_p it has just formed, and the stress pass does nothing: the same operations in the
    same order (`reproducible`, as above), so the state is that of the step with the pass, to the bit.
    (In 2D MUSL's kinematics pass without MLS is `g2p_kinematics`, which leaves the update to the
    material's pass: the tests of the vectorised kinematics pass below.)"""
    method = METHODS.get(method) or {**METHODS["usl-quadratic-mls"], "transfer": "apic"}
    scene = load_scene({**(SCENE_2D if dimension == 2 else SCENE_3D), "method": method,
                        "parallel": {"threads": threads}})
    inside, passed = stepped_with_and_without(scene, "updates_stress")
    assert np.abs(inside.particles.stress).max() > 1.0   # (the bodies have collided: a stress to compare)
    for name in ("x", "v", "F", "L", "stress", "volume"):
        assert np.array_equal(getattr(inside.particles, name), getattr(passed.particles, name)), name


@pytest.mark.parametrize("extra,updates", [
    ({"damping": {"type": "viscous", "coefficient": 5.0}}, False),               # after_g2p, after USL's pass
    ({"damping": {"type": "viscous", "coefficient": 5.0},
      "method": METHODS["musl-quadratic-mls"]}, True),                           # MUSL: before the kinematics
    ({"method": {**METHODS["usl-linear-pic"], "fbar": True}}, False),           # hooks after the kinematics
    ({"materials": {"m": SCENE_2D["materials"]["m"], "n": NEO_HOOKEAN}}, False),   # two materials
    ({"materials": {"m": {**SCENE_2D["materials"]["m"], "model": "j2_plasticity", "yield_stress": 10.0}}},
     False),                                                                     # a model over linear elasticity
])
def test_the_stress_pass_runs_where_g2p_cannot_update_the_stress(extra, updates):
    scene = copy.deepcopy(SCENE_2D)
    scene["method"] = METHODS["usl-linear-pic"]
    scene.update(copy.deepcopy(extra))
    if "n" in scene["materials"]:
        scene["bodies"][1]["material"] = "n"
    sim = ExplicitMPM(load_scene(scene))
    assert sim.phases.updates_stress() is updates
    before = sim.particles.stress.copy()
    sim.advance(2e-4)
    assert not np.array_equal(sim.particles.stress, before)


def test_an_initial_stress_is_read_by_the_first_p2g():
    """P2G forms the stress only where it is a function of the state (Particles.derived): a
    stress set before the first step is the state, and is what the first step's P2G reads."""
    scene = copy.deepcopy(SCENE_2D)
    scene["materials"] = {"m": NEO_HOOKEAN}
    scene["method"] = METHODS["usl-quadratic-mls"]
    prestressed, free = ExplicitMPM(load_scene(scene)), ExplicitMPM(load_scene(scene))
    prestressed.particles.stress[:, 0, 0] = -1e3
    prestressed.advance(2e-4)
    free.advance(2e-4)
    assert not np.array_equal(prestressed.particles.v, free.particles.v)


def p2g_variants(sim, steps: int) -> list:
    """The variant (the kernel's compile-time constants) that each of `steps` steps' P2G ran."""
    kernels, name, seen = sim.phases._kernels, sim.phases.plan.p2g, []

    class Recording:
        def __getattr__(self, attr):
            kernel = getattr(kernels, attr)
            if attr != name:
                return kernel

            def recorded(variant, *args):
                seen.append(variant)
                return kernel(variant, *args)
            return recorded

    sim.phases._kernels = Recording()
    for _ in range(steps):
        sim.advance(2e-4)
    return seen


@pytest.mark.parametrize("material,method", [(NEO_HOOKEAN, "usl-quadratic-mls"), (FLUID, "musl-quadratic-apic")])
def test_a_body_at_rest_has_its_stress_formed_from_the_first_p2g(material, method):
    """Bodies that start in their reference configuration (F = I, V = V0, L = 0) without a stress
    hold the stress their material's lines give there, zero: the first P2G forms it as every later
    one does, so a run compiles one P2G variant, not a second for its first step. A stress set
    before the first step is read by that step (and formed from the next)."""
    scene = copy.deepcopy(SCENE_2D)
    scene["materials"]["m"] = material
    scene = load_scene({**scene, "method": METHODS[method]})
    at_rest, prestressed = ExplicitMPM(scene), ExplicitMPM(scene)
    prestressed.particles.stress[:, 0, 0] = -1e3
    assert at_rest.phases.forms_stress() and not at_rest.particles.derived("stress")
    first, *later = p2g_variants(at_rest, 3)
    assert all(variant is first for variant in later)
    first, *later = p2g_variants(prestressed, 3)
    assert all(variant is later[0] for variant in later) and first is not later[0]


@pytest.mark.parametrize("material,disturb", [
    (NEO_HOOKEAN, lambda p: p.F.__setitem__((3, 0, 1), 1e-3)),
    (FLUID, lambda p: p.L.__setitem__((3, 1, 0), 0.5)),                # (viscous)
    (LINEAR_FLUID, lambda p: p.volume.__setitem__(3, 1.01 * p.volume[3]))])
def test_a_material_is_stress_free_where_its_own_stress_pass_gives_zero(material, disturb):
    """`stress_free` (what lets the first P2G form the stress): true at the bodies' first state,
    where the material's stress pass gives zero in every entry; false once one particle's state
    is disturbed, where that pass gives that particle a stress."""
    scene = copy.deepcopy(SCENE_2D)
    scene["materials"]["m"] = material
    sim = ExplicitMPM(load_scene({**scene, "method": METHODS["usl-linear-pic"]}))
    p, model = sim.particles, sim.phases._stress_model
    assert model.stress_free(p.F, p.L, p.volume, p.volume0)
    model.update_stress(p, slice(0, p.count), 2e-4)
    assert not np.any(p.stress)
    disturb(p)
    assert not model.stress_free(p.F, p.L, p.volume, p.volume0)
    model.update_stress(p, slice(0, p.count), 2e-4)
    assert np.any(p.stress[3]) and not np.any(np.delete(p.stress, 3, axis=0))


@pytest.mark.parametrize("material,dimension,method", [
    (NEO_HOOKEAN, 3, "musl-quadratic-apic"), (FLUID, 2, "usl-quadratic-mls")])
def test_reading_the_stress_formed_in_p2g_leaves_the_run_s_bits(material, dimension, method, monkeypatch):
    """With FMA contraction the stress P2G forms and the one the material's pass stores for a
    reader (a frame, a checkpoint) differ in their last bits. P2G forms it again after a read
    (Particles.derived), so a run read every few steps keeps the bits of one never read."""
    monkeypatch.setenv(fused_template.FMA, "1")
    scene = copy.deepcopy(SCENE_2D if dimension == 2 else SCENE_3D)
    scene["materials"]["m"] = material
    scene = load_scene({**scene, "method": METHODS[method]})
    read, unread = ExplicitMPM(scene), ExplicitMPM(scene)
    assert read.phases.forms_stress()
    for step in range(STEPS):
        read.advance(2e-4)
        unread.advance(2e-4)
        if step % 5 == 0:
            assert np.abs(read.particles.stress).max() >= 0.0   # the material's pass runs, as for a frame
            assert read.particles.derived("stress") and not read.particles.pending("stress")
    assert np.abs(unread.particles.stress).max() > 1.0   # (the bodies have collided)
    for name in ("x", "v", "F", "stress"):
        assert np.array_equal(getattr(read.particles, name), getattr(unread.particles, name)), name


def test_a_derived_stress_stays_derived_when_reordered_and_is_state_once_assigned():
    """Particles.take (sorting, a process's slab) moves rows of the same state: a stress that was
    a function of the state still is. An assigned stress is the state, and P2G reads it."""
    scene = copy.deepcopy(SCENE_2D)
    scene["materials"] = {"m": NEO_HOOKEAN}
    sim = ExplicitMPM(load_scene({**scene, "method": METHODS["usl-quadratic-mls"]}))
    assert not sim.particles.derived("stress")   # before the first stress pass
    sim.advance(2e-4)
    assert sim.particles.pending("stress") and sim.particles.derived("stress")
    sim.particles.take(np.arange(sim.particles.count)[::-1])
    assert sim.particles.derived("stress") and not sim.particles.pending("stress")
    sim.particles.stress = sim.particles.stress.copy()
    assert not sim.particles.derived("stress")


@pytest.mark.parametrize("material,dimension,method", [
    (NEO_HOOKEAN, 3, "musl-quadratic-apic"), (FLUID, 2, "usl-quadratic-mls"), (None, 3, "musl-linear-flip")])
def test_contracted_kernels_give_the_reproducible_ones_to_round_off(material, dimension, method, monkeypatch):
    """FMA contraction rounds a * b + c once instead of twice: over STEPS steps of a collision the
    state moves by round-off only (and the two runs use two different modules)."""
    scene = copy.deepcopy(SCENE_2D if dimension == 2 else SCENE_3D)
    if material:
        scene["materials"]["m"] = material
    scene = load_scene({**scene, "method": METHODS[method]})
    monkeypatch.setenv(fused_template.FMA, "1")
    contracted = ExplicitMPM(scene)
    monkeypatch.setenv(fused_template.FMA, "0")
    exact = ExplicitMPM(scene)
    assert contracted.phases._kernels is not exact.phases._kernels
    for _ in range(STEPS):
        contracted.advance(2e-4)
        exact.advance(2e-4)
    assert np.abs(exact.particles.stress).max() > 1.0   # (the bodies have collided)
    for name in ("x", "v", "F", "stress", "volume"):
        assert relative_difference(getattr(contracted.particles, name), getattr(exact.particles, name)) <= TOLERANCE, name


# -- MLS's USL pass vectorised (2D) ------------------------------------------------------------

def _counted(sim, kernel: str) -> list:
    """The calls the simulation makes to its module's `kernel` from now on (each one still runs)."""
    calls, real = [], getattr(sim.phases._kernels, kernel)
    sim.phases._kernels = SimpleNamespace(**vars(sim.phases._kernels))
    setattr(sim.phases._kernels, kernel, lambda *args: calls.append(real(*args)))
    return calls


def neo_hookean_mls(base: dict) -> dict:
    """The scene `base` of neo-Hookean bodies, stepped with MLS under USL."""
    scene = {**copy.deepcopy(base), "method": METHODS["usl-quadratic-mls"]}
    scene["materials"]["m"] = NEO_HOOKEAN
    return scene


def assert_one_more_step_the_same_bits(split, one_pass, kernel: str) -> None:
    """One more step of each: `split` calls its module's `kernel` once, and the particles' state is
    the same bits in both."""
    calls = _counted(split, kernel)
    split.advance(2e-4)
    one_pass.advance(2e-4)
    assert len(calls) == 1
    for name in ("x", "v", "F", "L", "stress", "volume"):
        assert np.array_equal(getattr(split.particles, name), getattr(one_pass.particles, name)), name


@pytest.mark.parametrize("material,threads,contract", [
    (NEO_HOOKEAN, 1, "1"), (NEO_HOOKEAN, 1, "0"), (FLUID, 2, "0"), (LINEAR_FLUID, 1, "0")])
def test_the_vectorised_mls_pass_gives_the_one_pass_kernel_bit_for_bit(material, threads, contract, monkeypatch):
    """`g2p_mls` sums the same products in the same order as `g2p` does with l_is_c (the rows of
    the stencil in `_stencil`'s order, the x weights from `_quadratic`, uncontracted), so the state
    after STEPS steps is the same bits, with FMA contraction (the default) and without."""
    monkeypatch.setenv(fused_template.FMA, contract)
    scene = copy.deepcopy(SCENE_2D)
    scene["materials"]["m"] = material
    scene = load_scene({**scene, "method": METHODS["usl-quadratic-mls"], "parallel": {"threads": threads}})
    split, one_pass = stepped_with_and_without(scene, "g2p_mls")
    assert_one_more_step_the_same_bits(split, one_pass, "g2p_mls")


@pytest.mark.parametrize("change", [
    {"dimension": 3},                                          # scalar gathers are faster in 3D
    {"method": METHODS["musl-quadratic-mls"]},                 # MUSL's passes
    {"method": {**METHODS["usl-quadratic-mls"], "transfer": "apic"}},
    {"materials": {"m": {"model": "linear_elastic", "density": 1000, "youngs_modulus": 1e4, "poisson_ratio": 0.3}}},
])
def test_the_vectorised_mls_pass_runs_only_for_mls_under_usl_in_2d(change):
    """It replaces the one-pass kernel only where that one would not write L_p (MLS, USL, the stress
    formed in P2G) nor update the stress, in 2D: elsewhere the scene keeps `g2p`."""
    base = neo_hookean_mls(SCENE_2D)
    sim = ExplicitMPM(load_scene(base))
    assert sim.phases.plan.g2p_usl == "g2p_mls"
    other = neo_hookean_mls(SCENE_3D) if change.get("dimension") == 3 else {**base, **change}
    sim = ExplicitMPM(load_scene(other))
    calls = _counted(sim, "g2p_mls") if hasattr(sim.phases._kernels, "g2p_mls") else []
    sim.advance(2e-4)
    assert calls == []


@pytest.mark.parametrize("threads", [1, 2])
def test_the_vectorised_mls_pass_names_the_first_inverted_particle_as_the_one_pass_kernel(threads):
    """The vectorised loop counts the particles whose J = det F is not positive and looks for the
    first one afterwards: the step fails naming the particle `g2p` names (with two threads the
    first of the first block that has one). The fluid's stress reads V_p / V0_p, not F_p, so the
    F_p turned over here reaches G2P finite."""
    scene = {**copy.deepcopy(SCENE_2D), "method": METHODS["usl-quadratic-mls"], "parallel": {"threads": threads}}
    scene["materials"]["m"] = FLUID
    assert_the_same_inverted_particle_named(scene, "g2p_mls")


def stepped_once(scene: dict, switch: str, on: bool) -> ExplicitMPM:
    """The scene's simulation after one step, with the fused plan's `switch` (on) or without it."""
    sim = ExplicitMPM(load_scene(scene))
    if not on:
        sim.phases.replan(without=(switch,))
    sim.advance(2e-4)
    return sim


def assert_the_same_inverted_particle_named(scene: dict, switch: str) -> None:
    """With the fused plan's `switch` and without it, F_p turned over for three particles: the step
    fails naming the first of them, the same particle both ways."""
    named = []
    for split in (True, False):
        sim = stepped_once(scene, switch, split)
        assert sim.phases.plan.makes(switch) is split
        n = sim.particles.count
        for p in (n - 4, n - 2, n // 3):   # in the last block, and one earlier (the first block with two threads)
            sim.particles.F[p] = np.diag([-1.0] + [1.0] * (sim.scene.dimension - 1))
        with pytest.raises(Instability, match="J = det F") as failure:
            sim.advance(2e-4)
        named.append(failure.value.particle_id)
    assert named == [int(sim.particles.id[n // 3])] * 2


# -- MLS's P2G, its work per particle vectorised (2D) ----------------------------------------

def _outside_log_interval(F: np.ndarray) -> int:
    J = np.linalg.det(F)
    return int(np.sum((J < near_one_log.LOW) | (J >= near_one_log.HIGH)))


@pytest.mark.parametrize("material,threads,contract", [
    (NEO_HOOKEAN, 1, "0"), (NEO_HOOKEAN, 1, "1"), (FLUID, 2, "0"), (LINEAR_FLUID, 1, "0")])
def test_the_vectorised_mls_p2g_gives_the_scalar_kernel_bit_for_bit(material, threads, contract, monkeypatch):
    """`p2g_mls` forms sigma_p, the weights, m v_p + dt m b_p and m C_p - dt V sigma_p D_p^-1 with the
    operations of `p2g` in its order (log J from log_near_one, libm's own bits) and scatters them as
    it does: after STEPS steps of the collision under gravity the state is the same bits, with FMA
    contraction and without. The neo-Hookean bodies are squeezed past log_near_one's interval, so
    the particles whose log J comes from math.log after the vectorised pass are in it too."""
    monkeypatch.setenv(fused_template.FMA, contract)
    without_lanes(monkeypatch)
    scene = copy.deepcopy(SCENE_2D)
    scene["materials"]["m"] = material
    scene = load_scene({**scene, "method": METHODS["usl-quadratic-mls"], "parallel": {"threads": threads}})
    vectorised, scalar = stepped_with_and_without(scene, "p2g_mls")
    assert vectorised.phases._p2g_mls_variants[True, True][2].ndim - 1 == near_one_log.matches_libm()
    calls = _counted(vectorised, "p2g_mls")
    vectorised.advance(2e-4)
    scalar.advance(2e-4)
    assert len(calls) == 1
    if material is NEO_HOOKEAN:
        assert _outside_log_interval(vectorised.particles.F) > 0
    for name in ("x", "v", "F", "stress", "volume"):
        assert np.array_equal(getattr(vectorised.particles, name), getattr(scalar.particles, name)), name


def test_the_vectorised_mls_p2g_reads_an_assigned_stress_as_the_scalar_kernel_does(monkeypatch):
    """An assigned stress is the state (Particles.derived): both kernels read it instead of forming it."""
    without_lanes(monkeypatch)
    scene = {**copy.deepcopy(SCENE_2D), "method": METHODS["usl-quadratic-mls"]}
    scene["materials"]["m"] = NEO_HOOKEAN
    sims = []
    for vectorised in (True, False):
        sim = ExplicitMPM(load_scene(scene))
        if not vectorised:
            sim.phases.replan(without=("p2g_mls",))
        sim.advance(2e-4)
        sim.particles.stress = sim.particles.stress * 1.5
        assert not sim.particles.derived("stress")
        calls = _counted(sim, "p2g_mls")
        sim.advance(2e-4)
        assert len(calls) == int(vectorised)
        sims.append(sim)
    for name in ("x", "v", "F"):
        assert np.array_equal(getattr(sims[0].particles, name), getattr(sims[1].particles, name)), name


@pytest.mark.parametrize("change,runs", [
    ({}, True),
    ({"method": METHODS["musl-quadratic-mls"]}, True),                  # P2G is the same in MUSL
    ({"materials": {"m": {"model": "linear_elastic", "density": 1000, "youngs_modulus": 1e4,
                          "poisson_ratio": 0.3}}}, True),                # the stored stress read
    ({"dimension": 3}, False),
    ({"method": {**METHODS["usl-quadratic-mls"], "transfer": "apic"}}, False),
    ({"damping": {"type": "viscous", "coefficient": 5.0}}, False),     # damping reads f_I: not folded
])
def test_the_vectorised_mls_p2g_runs_for_mls_with_the_force_folded_in_2d(change, runs, monkeypatch):
    without_lanes(monkeypatch)
    base = {**copy.deepcopy(SCENE_2D), "method": METHODS["usl-quadratic-mls"]}
    base["materials"]["m"] = NEO_HOOKEAN
    if change.get("dimension") == 3:
        scene = {**copy.deepcopy(SCENE_3D), "method": METHODS["usl-quadratic-mls"]}
    else:
        scene = {**base, **change}
    sim = ExplicitMPM(load_scene(scene))
    calls = _counted(sim, "p2g_mls") if hasattr(sim.phases._kernels, "p2g_mls") else []
    sim.advance(2e-4)
    assert len(calls) == int(runs)


@pytest.mark.parametrize("threads", [1, 2])
def test_the_vectorised_mls_p2g_names_the_first_particle_outside_the_grid_as_the_scalar_kernel(threads, monkeypatch):
    """The vectorised pass counts the particles outside the grid, and the chunk that has one looks
    for the first: the step fails naming the particle `p2g` names."""
    without_lanes(monkeypatch)
    scene = {**copy.deepcopy(SCENE_2D), "method": METHODS["usl-quadratic-mls"], "parallel": {"threads": threads}}
    scene["materials"]["m"] = FLUID
    assert_the_same_particle_named_outside_the_grid(scene, "p2g_mls", "p2g_mls", lambda n: (
        (n - 3, [2.0, 0.2]), (n - 1, [float("nan"), 0.2]), (n // 3 + 70, [0.5, -1.0])))


def without_lanes(monkeypatch) -> None:
    """2D's folded MLS P2G as `p2g_mls`, not `p2g_mls_lanes` (the tests of p2g_mls compare it with
    `p2g`; those of the lanes compare the lanes with it)."""
    plan = FusedPhases._plan
    monkeypatch.setattr(FusedPhases, "_plan", lambda self, without: plan(self, without | {"lanes"}))


def assert_the_same_particle_named_outside_the_grid(scene: dict, switch: str, kernel: str, moved) -> None:
    """With the fused plan's `switch` and without it, the particles `moved(count)` names put where it
    says (index, position): the step fails naming the first of them, the same particle both ways,
    and `kernel` runs only with the switch on."""
    named = []
    for on in (True, False):
        sim = stepped_once(scene, switch, on)
        places = moved(sim.particles.count)
        for p, x in places:
            sim.particles.x[p] = x
        calls = _counted(sim, kernel)
        with pytest.raises(Instability, match="left the grid") as failure:
            sim.advance(2e-4)
        assert len(calls) == int(on)
        named.append(failure.value.particle_id)
    assert named == [int(sim.particles.id[min(p for p, _ in places)])] * 2


# -- MUSL's kinematics pass, vectorised (2D) ------------------------------------------------

@pytest.mark.parametrize("material,method,threads,contract", [
    (NEO_HOOKEAN, "musl-linear-flip", 1, "1"), (NEO_HOOKEAN, "musl-quadratic-apic", 1, "1"),
    (FLUID, "musl-linear-flip", 1, "0"), (None, "musl-linear-flip", 2, "0"), (None, "musl-quadratic-apic", 1, "0")])
def test_the_vectorised_kinematics_pass_gives_the_scalar_kernel_bit_for_bit(material, method, threads, contract,
                                                                             monkeypatch):
    """`g2p_kinematics` sums the same products in the same order as `g2p`'s KINEMATICS pass (the rows
    of the stencil in `_stencil`'s order, `_axis`'s weights and gradients for linear hats and
    quadratic B-splines), so the state after STEPS steps is the same bits. Linear elasticity (None:
    the scene's own material) then has its stress updated by its own pass instead of in G2P: the same
    bits without FMA contraction (`updates_stress`)."""
    monkeypatch.setenv(fused_template.FMA, contract)
    scene = copy.deepcopy(SCENE_2D)
    if material is not None:
        scene["materials"]["m"] = material
    scene = load_scene({**scene, "method": METHODS[method], "parallel": {"threads": threads}})
    split, one_pass = stepped_with_and_without(scene, "g2p_kinematics")
    assert not split.phases.updates_stress() and one_pass.phases.updates_stress() is (material is None)
    assert_one_more_step_the_same_bits(split, one_pass, "g2p_kinematics")


@pytest.mark.parametrize("change", [
    {"dimension": 3},                                          # not measured faster in 3D: not emitted
    {"method": METHODS["usl-quadratic-flip"]},                 # USL has no KINEMATICS pass
    {"method": METHODS["musl-quadratic-mls"]},                 # MLS's L_p is B_p D_p^-1
])
def test_the_vectorised_kinematics_pass_runs_only_under_musl_without_mls_in_2d(change):
    """It replaces `g2p`'s KINEMATICS pass under MUSL without MLS, in 2D; elsewhere the scene keeps
    `g2p`, and linear elasticity its stress update in G2P."""
    base = {**copy.deepcopy(SCENE_2D), "method": METHODS["musl-linear-flip"]}
    sim = ExplicitMPM(load_scene(base))
    assert sim.phases.plan.g2p_kinematics == "g2p_kinematics" and not sim.phases.updates_stress()
    other = {**copy.deepcopy(SCENE_3D), "method": METHODS["musl-linear-flip"]} if "dimension" in change \
        else {**base, **change}
    sim = ExplicitMPM(load_scene(other))
    calls = _counted(sim, "g2p_kinematics") if hasattr(sim.phases._kernels, "g2p_kinematics") else []
    sim.advance(2e-4)
    assert calls == [] and sim.phases.updates_stress()


@pytest.mark.parametrize("threads", [1, 2])
def test_the_vectorised_kinematics_pass_names_the_first_inverted_particle_as_the_scalar_kernel(threads):
    """The vectorised loop counts the particles whose J = det F is not positive and looks for the
    first one afterwards: the step fails naming the particle `g2p` names."""
    scene = {**copy.deepcopy(SCENE_2D), "method": METHODS["musl-linear-flip"], "parallel": {"threads": threads}}
    assert_the_same_inverted_particle_named(scene, "g2p_kinematics")


# -- MLS in 3D, a node's values in four lanes ------------------------------------------------

# The lanes change the scatter and the gather only: a material's stress lines are the same text in
# `p2g_lanes` and `p2g` (held to the stress pass by the stress-formed tests above), so the cases cover
# contraction on and off, one and two threads and the gather on and off, not every material. The
# linear fluid on two threads without contraction (the suite's MPM_FMA=0, tests/conftest.py) is
# the module and the parallel forms the failing-particle test below compiles too (a 3D module and
# its parallel kernels take about 50 s to compile on this 2-core machine).
@pytest.mark.parametrize("material,threads,contract,gathers", [
    (NEO_HOOKEAN, 1, "0", True), (LINEAR_FLUID, 2, "0", True),
    (None, 1, "1", False)])   # linear elasticity: its stress read in P2G, updated in G2P (`g2p` keeps it)
def test_the_lanes_kernels_give_the_scalar_kernels_bit_for_bit(material, threads, contract, gathers, monkeypatch):
    """`p2g_lanes` adds a node's (m, mv) as lanes of one vector, each lane doing `p2g`'s operations on
    its component, and sums the threads' rows in `_reduce_mass_momentum`'s order; `g2p_lanes` gathers
    a node's velocity as one vector, each lane doing `g2p`'s. After STEPS steps of the collision
    under gravity the state is the same bits, with FMA contraction and without."""
    monkeypatch.setenv(fused_template.FMA, contract)
    scene = copy.deepcopy(SCENE_3D)
    if material is not None:
        scene["materials"]["m"] = material
    scene = load_scene({**scene, "method": METHODS["usl-quadratic-mls"], "parallel": {"threads": threads}})
    lanes, scalar = stepped_with_and_without(scene, "lanes")
    gathered = _counted(lanes, "g2p_lanes")
    assert_one_more_step_the_same_bits(lanes, scalar, "p2g_lanes")
    assert len(gathered) == int(gathers)
    assert np.array_equal(lanes.phases._affine_matrix, scalar.phases._affine_matrix)
    assert np.array_equal(lanes.grid.momentum, scalar.grid.momentum)


@pytest.mark.parametrize("change,scatters,gathers", [
    ({"method": METHODS["musl-quadratic-mls"]}, True, False),            # MUSL's passes are `g2p`'s
    ({"method": {**METHODS["usl-quadratic-mls"], "transfer": "apic"}}, False, False),
    ({"damping": {"type": "viscous", "coefficient": 5.0}}, False, True),  # damping reads f_I: not folded
    ({"dimension": 2}, False, False),                                   # 2D has its own vectorised passes
])
def test_the_lanes_kernels_run_for_mls_in_3d_only(change, scatters, gathers):
    scene = neo_hookean_mls(SCENE_2D) if change.get("dimension") == 2 else {**neo_hookean_mls(SCENE_3D), **change}
    sim = ExplicitMPM(load_scene(scene))
    has = hasattr(sim.phases._kernels, "p2g_lanes")
    assert has is (sim.scene.dimension == 3)
    scattered = _counted(sim, "p2g_lanes") if has else []
    gathered = _counted(sim, "g2p_lanes") if has else []
    sim.advance(2e-4)
    assert (len(scattered), len(gathered)) == (int(scatters), int(gathers))


def test_a_conducting_3d_scene_has_no_lanes_kernels():
    assert "p2g_lanes" not in fused_template.source(3, thermal=True)
    assert "p2g_lanes" not in fused_template.source(3, contact=True)
    assert "p2g_lanes" in fused_template.source(3)
    assert "p2g_mls_lanes" not in fused_template.source(2, thermal=True)
    assert "p2g_mls_lanes" in fused_template.source(2)


@pytest.mark.parametrize("threads", [1, 2])
def test_the_lanes_kernels_name_the_first_failing_particle_as_the_scalar_kernels(threads):
    """`g2p_lanes` names the first particle whose J = det F is not positive, `p2g_lanes` the first
    outside the grid, as `g2p` and `p2g` do (the fluid's stress reads V_p / V0_p, not F_p, so the
    F_p turned over reaches G2P finite)."""
    scene = {**copy.deepcopy(SCENE_3D), "method": METHODS["usl-quadratic-mls"], "parallel": {"threads": threads}}
    scene["materials"]["m"] = LINEAR_FLUID
    assert_the_same_inverted_particle_named(scene, "lanes")
    assert_the_same_particle_named_outside_the_grid(scene, "lanes", "p2g_lanes", lambda n: (
        (n - 3, [2.0, 0.2, 0.2]), (n - 1, [float("nan"), 0.2, 0.2]), (n // 3, [0.5, -1.0, 0.2])))


# -- MLS in 2D, P2G's scatter in four lanes --------------------------------------------------

@pytest.mark.parametrize("material,threads,contract", [
    (NEO_HOOKEAN, 1, "1"), (NEO_HOOKEAN, 1, "0"), (FLUID, 2, "0"), (LINEAR_FLUID, 1, "0")])
def test_the_2d_lanes_scatter_gives_the_vectorised_mls_p2g_bit_for_bit(material, threads, contract, monkeypatch):
    """`p2g_mls_lanes` adds a node's (m, mv_x, mv_y, 0) as lanes of one vector, each lane doing
    `p2g_mls`'s operations on its component, and sums the threads' rows in `_reduce_mass_momentum`'s
    order: after STEPS steps of the collision under gravity the state and the grid are the same
    bits, with FMA contraction and without."""
    monkeypatch.setenv(fused_template.FMA, contract)
    scene = copy.deepcopy(SCENE_2D)
    scene["materials"]["m"] = material
    scene = load_scene({**scene, "method": METHODS["usl-quadratic-mls"], "parallel": {"threads": threads}})
    lanes, plain = stepped_with_and_without(scene, "lanes")
    scattered = _counted(plain, "p2g_mls")
    assert_one_more_step_the_same_bits(lanes, plain, "p2g_mls_lanes")
    assert len(scattered) == 1
    assert np.array_equal(lanes.grid.mass, plain.grid.mass)
    assert np.array_equal(lanes.grid.momentum, plain.grid.momentum)


@pytest.mark.parametrize("change,runs", [
    ({}, True),
    ({"method": METHODS["musl-quadratic-mls"]}, True),                 # P2G is the same in MUSL
    ({"method": {**METHODS["usl-quadratic-mls"], "transfer": "apic"}}, False),
    ({"damping": {"type": "viscous", "coefficient": 5.0}}, False),    # damping reads f_I: not folded
])
def test_the_2d_lanes_scatter_runs_where_the_vectorised_mls_p2g_does(change, runs):
    sim = ExplicitMPM(load_scene({**neo_hookean_mls(SCENE_2D), **change}))
    assert not hasattr(sim.phases._kernels, "g2p_lanes")   # 2D's G2P is `g2p_mls`
    calls = _counted(sim, "p2g_mls_lanes")
    sim.advance(2e-4)
    assert len(calls) == int(runs)


def test_a_2d_plan_without_p2g_mls_runs_p2g_with_the_lanes_on():
    """Where the plan leaves `p2g_mls` out (as a call does whose arrays it cannot take a flat view
    of), 2D's folded P2G is `p2g`: a 2D module has no `p2g_lanes`."""
    sim = ExplicitMPM(load_scene(neo_hookean_mls(SCENE_2D)))
    sim.phases.replan(without=("p2g_mls",))
    assert sim.phases._has_lanes and not hasattr(sim.phases._kernels, "p2g_lanes")
    assert sim.phases.plan.p2g == "p2g" and sim.phases.plan.fold
    calls = _counted(sim, "p2g")
    sim.advance(2e-4)
    assert len(calls) == 1


@pytest.mark.parametrize("threads", [1, 2])
def test_the_2d_lanes_scatter_names_the_first_particle_outside_the_grid_as_p2g_mls(threads):
    scene = {**copy.deepcopy(SCENE_2D), "method": METHODS["usl-quadratic-mls"], "parallel": {"threads": threads}}
    scene["materials"]["m"] = FLUID
    assert_the_same_particle_named_outside_the_grid(scene, "lanes", "p2g_mls_lanes", lambda n: (
        (n - 3, [2.0, 0.2]), (n - 1, [float("nan"), 0.2]), (n // 3 + 70, [0.5, -1.0])))
