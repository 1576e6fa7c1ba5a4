"""`mpm import karamelo`, command by command: what each translated command becomes, what it
notes, and where it stops (solver/karamelo.py)."""
from __future__ import annotations

import math

import pytest

from solver.karamelo import DEFAULT_DT_FACTOR, MAX_FRAMES, KarameloError, translate
from solver.scene_checks import load_scene
from solver.stability import stable_limit

# a 2D elastic block on a 1 x 1 grid of 0.1 cells: K + 4/3 G = E (1 - nu) / ((1 + nu)(1 - 2 nu))
BLOCK = """
E = 1e6
nu = 0.25
dimension(2, 0, 1, 0, 1, 0.1)
region(b, block, 0.2, 0.8, 0.2, 0.8)
material(m, linear, 1000, E, nu)
solid(s, region, b, 2, m, 0.1)
group(gs, particles, region, b, solid, s)
"""
# Karamelo's Taylor bar copper (GPa, mm, ms), m = 0 and cv = 0; {q}: the EOS's Q1, Q2
COPPER = """eos(e, shock, 8.94e-06, 100, 3933, 1.5, 0, 0, 25, {q})
strength(s, johnson_cook, 44, 0.065, 0.356, 0.37, 1e-3, 0, 0, 25, 1600)
material(m, eos-strength, e, s)
"""
SPEED = math.sqrt(1e6 * 0.75 / (1.25 * 0.5) / 1000)


def reasons(items) -> dict[int, str]:
    return {item.line: item.reason for item in items}


def test_force_nodes_is_a_force_load_on_the_particles_that_reach_the_nodes():
    t = translate(BLOCK + """region(tip, block, 0.75, INF, 0.75, INF)
group(gt, nodes, region, tip, solid, s)
F = -100
fix(f, force_nodes, gt, NULL, F*min(time, 1), 0)
run_time(1)
""")
    (load,) = t.scene["loads"]
    # the block's bounds one cell (the linear shape's reach) wider, INF: a cell beyond the grid
    assert load == {"type": "force", "body": "s", "where": {"type": "box", "lower": [0.65, 0.65],
                                                             "upper": [1.1, 1.1]},
                    "force": [0.0, "-100.0 * min ( t , 1 )"]}
    assert "shares the total force equally among the nodes of 'gt'" in reasons(t.notes)[12]
    load_scene(t.scene)


def test_force_nodes_needs_a_group_of_one_solid():
    t = translate(BLOCK + "region(tip, block, 0.75, INF, 0.75, INF)\ngroup(gt, nodes, region, tip)\n"
                          "fix(f, force_nodes, gt, 0, -1, 0)\nrun_time(1)\n")
    assert "not of one translated solid" in reasons(t.untranslated)[11]
    assert "loads" not in t.scene


def test_velocity_nodes_on_disks_and_their_outside():
    t = translate("""dimension(2, -1, 1, -1, 1, 0.1)
region(ring, cylinder, 0, 0, 0.8)
region(hole, cylinder, 0, 0, 0.3)
region(out, cylinder, 0, 0, 0.8, exterior)
material(m, linear, 1000, 1e6, 0.3)
solid(s, region, ring, 2, m, 0.1)
delete_particles(s, region, hole)
group(gi, nodes, region, hole, solid, s)
group(go, nodes, region, out, solid, s)
fix(vi, velocity_nodes, gi, 0, 0)
fix(vo, velocity_nodes, go, sin(time), NULL)
run_time(1)
""")
    inner, outer = t.scene["boundary_conditions"]
    assert inner == {"type": "velocity", "where": {"type": "sphere", "center": [0.0, 0.0], "radius": 0.3},
                     "velocity": [0.0, 0.0]}
    assert outer["where"] == {"type": "difference", "parts": [
        {"type": "box", "lower": [-1.1, -1.1], "upper": [1.1, 1.1]},
        {"type": "sphere", "center": [0.0, 0.0], "radius": 0.8}]}
    assert outer["velocity"] == ["sin ( t )", None]
    scene = load_scene(t.scene)
    from solver.boundary import _inside
    from solver.state import make_grid
    nodes = make_grid(scene).node_positions()
    r = [math.hypot(*p) for p in nodes]
    inside = _inside(scene.boundary_conditions[1].where, nodes, 1e-9)
    assert all(flag == (radius > 0.8) for flag, radius in zip(inside, r))


def test_body_force_gravity_and_named_expressions():
    t = translate(BLOCK + "g = -9.81\nfix(b, body_force, all, 0, g)\nrun_time(1)\n")
    assert t.scene["gravity"] == [0.0, -9.81] and "body_force" not in t.scene
    t = translate(BLOCK + "r = sqrt(x*x + y*y)\nw = sin(PI*time)*r\nfix(b, body_force, all, w, NULL)\nrun_time(1)\n")
    assert t.scene["body_force"] == ["w", "0.0"]
    assert t.scene["expressions"] == {"r": "sqrt ( x * x + y * y )", "w": "sin ( pi * t ) * r"}
    assert set(reasons(t.notes)) == {0}   # (Karamelo's default dt_factor)
    load_scene(t.scene)


def test_a_tlmpm_body_force_reads_the_reference_position():
    t = translate("method(tlmpm, FLIP, linear, 1)\n" + BLOCK.replace("dimension(2, 0, 1, 0, 1, 0.1)", "dimension(2)")
                  + "r = sqrt(x*x + y*y)\nq = 2*time\nfix(b, body_force, all, r*q, q)\nrun_time(1)\n")
    assert t.scene["body_force"] == ["r_0 * q", "q"]
    assert t.scene["expressions"] == {"r": "sqrt ( x * x + y * y )", "r_0": "sqrt ( X * X + Y * Y )", "q": "2 * t"} \
        or t.scene["expressions"] == {"r_0": "sqrt ( X * X + Y * Y )", "q": "2 * t"}
    assert "reference grid" in reasons(t.notes)[12]
    load_scene(t.scene)


def test_variables_keep_their_names_and_a_redefinition_gets_a_new_one():
    t = translate(BLOCK + "e = 2*x\nv = e\nv = 3*e\nfix(v0, initial_velocity_particles, gs, v, e)\nrun_time(1)\n")
    # `e` is the scene's constant: the variable is e_k; the second v is v_
    assert t.scene["bodies"][0]["initial_velocity"] == ["v_", "e_k"]
    assert t.scene["expressions"] == {"e_k": "2 * x", "v_": "3 * e_k"}
    load_scene(t.scene)


def test_run_with_a_fixed_step_and_run_time_add_up():
    t = translate(BLOCK + "set_dt(1e-4)\nrun(100)\nrun_time(0.5)\n")
    assert t.scene["time"] == {"dt": 1e-4, "end": pytest.approx(0.51)}


def test_run_with_an_adaptive_step_is_that_many_first_steps():
    t = translate(BLOCK + "dt_factor(0.5)\nrun(200)\n")
    scene = load_scene(t.scene)
    first = 0.5 * stable_limit(scene).dt
    assert scene.time.cfl == pytest.approx(0.5) and stable_limit(scene).dt == pytest.approx(0.1 / SPEED)
    assert scene.time.end == pytest.approx(200 * first, rel=1e-12)
    assert "200 steps with an adaptive step" in reasons(t.notes)[10]


def test_dt_factor_uses_karamelos_wave_speed():
    """A Tait fluid: Karamelo's c = sqrt((K + 4/3 G) / rho), the scene's sqrt(K gamma / rho)."""
    t = translate("""dimension(2, 0, 1, 0, 1, 0.1)
region(w, block, 0, 0.5, 0, 0.5)
eos(e, fluid, 1000, 360, 7)
strength(s, fluid, 0.001)
material(m, eos-strength, e, s)
solid(s1, region, w, 2, m, 0.1)
dt_factor(0.1)
run_time(1)
""")
    ratio = math.sqrt(360 * 7 / 1000) / math.sqrt((360 + 4 * 0.001 / 3) / 1000)
    assert t.scene["time"]["cfl"] == pytest.approx(0.1 * ratio, rel=1e-12)
    assert "time.cfl = 0.26" in reasons(t.notes)[7]


def test_without_dt_factor_the_cfl_is_karamelos_default():
    t = translate(BLOCK + "run_time(1)\n")
    assert t.scene["time"]["cfl"] == DEFAULT_DT_FACTOR == 0.9
    assert "default 0.9" in reasons(t.notes)[0]


def test_dumps_give_frames_and_keep_the_fields_preview_needs():
    t = translate(BLOCK + "set_dt(1e-3)\ndump(d, all, particle, 100, p.*.LAMMPS, x, y, vx, seq, damage)\nrun(1000)\n")
    assert t.scene["output"] == {"fields": ["position", "velocity", "stress", "von_mises", "damage"], "frames": 11}
    t = translate(BLOCK + "set_dt(1e-5)\ndump(d, all, particle, 1, p.*.LAMMPS, x)\nrun(5000)\n")
    assert t.scene["output"]["frames"] == MAX_FRAMES and "5001 frames" in reasons(t.notes)[10]


def test_johnson_cook_with_m_and_cv_zero_is_isothermal_without_softening():
    t = translate("dimension(3, 0, 1, 0, 1, 0, 1, 0.25)\nregion(b, block, 0, 0.5, 0, 0.5, 0, 0.5)\n"
                  + COPPER.format(q="0, 0") + "solid(s1, region, b, 1, m, 0.25, 25)\nrun_time(1)\n")
    material = t.scene["materials"]["m"]
    assert "m" not in material and "specific_heat" not in material and material["taylor_quinney"] == 0.0
    assert material["eos"] == {"model": "mie_gruneisen", "c0": 3933.0, "s": 1.5, "gamma0": 0.0}
    # the scene's bulk modulus is rho c0^2 = 138, Karamelo's K = 100: 0.9 becomes 1.0, the largest
    assert t.scene["time"]["cfl"] == 1.0 and "% smaller than Karamelo's" in reasons(t.notes)[0]
    load_scene(t.scene)


def test_the_shock_eos_artificial_viscosity_is_refused_by_name():
    t = translate("dimension(3, 0, 1, 0, 1, 0, 1, 0.25)\n" + COPPER.format(q="1.5, 0.06") + "run_time(1)\n")
    assert "artificial viscosity Q1 = 1.5, Q2 = 0.06" in reasons(t.untranslated)[4]
    assert "m" not in t.scene["materials"]


# a wall of nodes fixed after a first run of {first} steps of 1e-4, then a second run
LATE_WALL = BLOCK + """set_dt(1e-4)
run({first})
region(w, block, 0.9, INF, -INF, INF)
group(gw, nodes, region, w, solid, s)
fix(wall, velocity_nodes, gw, 0, NULL)
{then}
"""


def test_a_fix_after_a_set_up_run_applies_from_the_start_with_a_note():
    t = translate(LATE_WALL.format(first=1, then="run(9999)"))
    assert len(t.scene["boundary_conditions"]) == 1 and t.scene["time"]["end"] == pytest.approx(1.0)
    assert "a set-up run" in reasons(t.notes)[13]


def test_a_fix_after_a_long_run_is_listed_not_applied():
    t = translate(LATE_WALL.format(first=5000, then="material(m2, linear, 1000, 1e6, 0.3)\nrun(5000)"))
    assert t.scene["boundary_conditions"] == []
    listed = reasons(t.untranslated)
    assert "would act from t = 0 instead of from t = 0.5" in listed[13]
    assert "material(...) after the run of line 10" in listed[14]


def test_old_solid_syntax_stops_naming_the_line_and_the_current_form():
    with pytest.raises(KarameloError) as caught:
        translate(BLOCK + "solid(s2, block, b, 2, m, 0.1)\n")
    assert str(caught.value) == ("line 9: solid(s2, block, ...) is old syntax that Karamelo at 08e444d no longer "
                                 "reads (a solid is seeded from a region by name): it writes "
                                 "solid(s2, region, b, 2, m, 0.1)")
