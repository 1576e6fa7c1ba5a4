"""`mpm import karamelo`: Karamelo's own example files (tests/data/karamelo/, from its
repository) translate into scenes; what has no translation is listed by line with a
reason; the translated two disks run exactly as examples/two_disks.json."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from solver import cli
from solver.karamelo import KarameloError, translate, translate_file
from solver.runner import make_simulation
from solver.scene import SceneError
from solver.scene_checks import load_scene

DATA = Path(__file__).resolve().parents[1] / "data" / "karamelo"
EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
FILES = sorted(DATA.glob("*.mpm"))
# What each file becomes: "valid" (its scene validates) or the start of the message it stops with.
OUTCOME = {"two-disks": "valid", "Bouncing_balls__ULMPM__bouncing_balls": "valid", "Dam-break__water-dam": "valid",
           "Cantilever__2D__cantilever_force_tip": "valid", "vortex__Linear__vortex": "valid",
           "Taylor-bar__cylindrical__ULMPM__cylindrical_taylor_bar": "valid",
           "Vertical_bar__ULMPM__vertical_bar": "line 34: solid(solid1, rectangle, ...) is old syntax"}
# Commands whose every use in these files has a scene equivalent: translated without a word.
SILENT = {"method", "scheme", "dimension", "region", "material", "eos", "strength", "damage", "solid",
          "delete_particles", "group", "compute", "set_dt", "dt_factor", "run_time", "run", "dump"}
SILENT_FIXES = {"initial_velocity_particles", "velocity_nodes", "body_force", "kinetic_energy", "strain_energy"}


def _accounted(translation) -> set[int]:
    return {item.line for item in translation.untranslated + translation.notes}


@pytest.mark.parametrize("path", FILES, ids=lambda p: p.stem)
def test_every_karamelo_example_imports_with_no_silent_loss(path):
    """Every line is translated, noted or listed (a line whose command has no scene equivalent
    is never passed over), the listed lines are quoted as written, and the file ends as
    OUTCOME says: a valid scene, or a stop naming its line."""
    lines = path.read_text().splitlines()
    try:
        translation = translate_file(path)
    except KarameloError as error:
        assert str(error).startswith(OUTCOME[path.stem])
        return
    for item in translation.untranslated + translation.notes:
        assert item.reason and 0 <= item.line <= len(lines)
        if item.text:   # the line as written, comment removed
            assert lines[item.line - 1].split("#")[0].strip() == item.text
    accounted = _accounted(translation)
    for number, raw in enumerate(lines, start=1):
        line = raw.split("#")[0].strip()
        command = line.split("(")[0].strip()
        if not line or "=" in line.split("(")[0]:
            continue   # a variable: it has no effect until a command uses it
        kind = line.split(",")[1].strip() if command == "fix" else None
        if command not in SILENT and not (command == "fix" and kind in SILENT_FIXES):
            assert number in accounted, f"line {number} {line!r} is neither translated, noted nor listed"
    assert OUTCOME[path.stem] == "valid"
    load_scene(translation.scene)


@pytest.mark.parametrize("path", [p for p in FILES if p.stem != "Vertical_bar__ULMPM__vertical_bar"], ids=lambda p: p.stem)
def test_every_imported_example_runs_a_few_steps(path):
    """A short run of each imported file (the Taylor bar on cells twice as large, to stay cheap):
    finite, and moving where the file makes it move."""
    text = path.read_text()
    if "Taylor" in path.stem:
        text = text.replace("N        = 4", "N        = 2")
    scene = load_scene(translate(text, name=path.stem).scene)
    sim = make_simulation(scene)
    x0 = sim.particles.x.copy()
    for _ in range(3):
        sim.advance(scene.time.dt or sim.stable_time_step(scene.time.cfl))
    assert np.all(np.isfinite(sim.particles.x))
    assert np.any(sim.particles.x != x0)   # every file loads or moves its bodies


def test_karamelos_tlmpm_taylor_bar_imports_in_tlmpm_and_runs():
    """Karamelo's TLMPM Taylor bar (examples/Taylor-bar/cylindrical/TLMPM/ in its repository, a
    3D cylinder like the ULMPM file here) differs from the ULMPM file in three lines: the method,
    the wall at the bar's end (x_wall = hLx: the reference grid ends there) and the wall's node
    group from half a cell before it. It imports as a 3D tlmpm scene and runs (cells twice as large)."""
    text = (DATA / "Taylor-bar__cylindrical__ULMPM__cylindrical_taylor_bar.mpm").read_text()
    for ulmpm, tlmpm in (("method(ulmpm, FLIP, linear, FLIP)", "method(tlmpm, FLIP, linear, FLIP)"),
                         ("x_wall = hLx + 3*cellsize", "x_wall = hLx"),
                         ("x_wall - cellsize, INF", "x_wall - 0.5*cellsize, INF"),
                         ("N        = 4", "N        = 2")):
        assert ulmpm in text
        text = text.replace(ulmpm, tlmpm)
    translation = translate(text, name="cylindrical_taylor_bar_tlmpm")
    scene = load_scene(translation.scene)
    assert scene.method.formulation == "tlmpm" and scene.dimension == 3 and not scene.axisymmetric
    sim = make_simulation(scene)
    assert sim.constraints.node.size == 31 * 31   # the wall: the reference grid's last node layer, x = hLx
    x0 = sim.particles.x.copy()
    for _ in range(3):
        sim.advance(sim.stable_time_step(scene.time.cfl))
    assert np.all(np.isfinite(sim.particles.x)) and np.any(sim.particles.x != x0)


def test_what_the_files_stop_on_or_note_is_named():
    with pytest.raises(KarameloError) as caught:
        translate_file(DATA / "Vertical_bar__ULMPM__vertical_bar.mpm")
    assert str(caught.value) == (
        "line 34: solid(solid1, rectangle, ...) is old syntax that Karamelo at 08e444d no longer reads (a solid "
        "is seeded from a region by name): it writes solid(solid1, region, box, 1, mat1, cellsize)")
    taylor = translate_file(DATA / "Taylor-bar__cylindrical__ULMPM__cylindrical_taylor_bar.mpm")
    notes = {item.line: item.reason for item in taylor.notes}
    assert "20000 steps with an adaptive step" in notes[89] and "a set-up run" in notes[88]
    cantilever = translate_file(DATA / "Cantilever__2D__cantilever_force_tip.mpm")
    assert any(i.line == 46 and "force_nodes" in i.reason for i in cantilever.notes)


def test_the_translated_two_disks_run_exactly_as_the_example():
    """Same grid, bodies, materials and method as examples/two_disks.json (Karamelo's
    default scheme is MUSL). The file's set_dt(0.01) is not the paper's 0.001 (its comment
    says 0.001; the example follows the paper): both run here with the example's dt,
    and every particle array is the same bits after 200 steps."""
    translated = translate_file(DATA / "two-disks.mpm").scene
    example = json.loads((EXAMPLES / "two_disks.json").read_text())
    assert translated["time"] == {"dt": 0.01, "end": 3.5}
    assert translated["method"] == example["method"] and translated["grid"] == example["grid"]
    (material,) = translated["materials"].values()
    assert material == example["materials"]["elastic"]
    translated["time"]["dt"] = example["time"]["dt"]
    states = []
    for scene in (translated, example):
        sim = make_simulation(load_scene(scene))
        for _ in range(200):
            sim.advance(0.001)
        states.append(sim.particles.arrays())
    assert states[0].keys() == states[1].keys()
    for name in states[0]:
        assert np.array_equal(states[0][name], states[1][name]), name


def test_variables_expressions_and_runtime_values():
    translation = translate("""
E = 2^3*1e2        # 800
nu = 0.25
r = sqrt(x*x + y*y)
g = sin(PI*time)
dimension(2, 0, 1, 0, 1, 0.1)
region(b, block, 0.2, 0.8, 0.2, 0.8)
material(m, linear, 1000, E, nu)
solid(s, region, b, 2, m, 0.1)
group(gb, particles, region, b, solid, s)
fix(v, initial_velocity_particles, gb, r, -r, NULL)
group(gn, nodes, region, b, solid, s)
fix(bc, velocity_nodes, gn, g, NULL)
tip = xcm(gb, x)
fix(w, velocity_nodes, gn, tip, NULL)
shake(all)
run_time(1)
""")
    scene = translation.scene
    assert scene["materials"]["m"]["youngs_modulus"] == 800.0
    # the variables in x, y, z, time keep their names: the scene's expressions
    assert scene["bodies"][0]["initial_velocity"] == ["r", "- r"]
    assert scene["boundary_conditions"][0]["velocity"] == ["g", None]
    assert scene["expressions"] == {"r": "sqrt ( x * x + y * y )", "g": "sin ( pi * t )"}
    assert [(i.line, i.reason.split(":")[0]) for i in translation.untranslated] == [
        (14, "xcm() is a group's centre of mass, computed during a Karamelo run"),
        (15, "velocity"), (16, "unknown command 'shake'")]
    load_scene(scene)


@pytest.mark.parametrize("text,message", [
    ("E = 3 $ 4", "line 1: unexpected character '$'"),
    ("E = nu * 2", "line 1: cannot read 'nu * 2': unknown name 'nu'"),
    ("this is not a command", "line 1: neither a variable definition"),
])
def test_unreadable_lines_name_their_line(text, message):
    with pytest.raises(KarameloError) as caught:
        translate(text)
    assert str(caught.value).startswith(message)


def test_mpm_import_writes_the_scene_and_lists_the_rest(tmp_path, capsys):
    out = tmp_path / "disks.json"
    assert cli.main(["import", "karamelo", str(DATA / "two-disks.mpm"), "-o", str(out)]) == cli.EXIT_PARTIAL
    load_scene(out)
    assert "two-disks.mpm:38: not translated: dump(dump2, all, grid" in capsys.readouterr().err
    assert cli.main(["import", "karamelo", str(DATA / "Vertical_bar__ULMPM__vertical_bar.mpm"),
                     "-o", str(tmp_path / "bar.json")]) == cli.EXIT_ERROR
    assert "line 34: solid(solid1, rectangle, ...) is old syntax" in capsys.readouterr().err
    assert cli.main(["import", "karamelo", str(DATA / "Cantilever__2D__cantilever_force_tip.mpm"),
                     "-o", str(tmp_path / "beam.json")]) == cli.EXIT_PARTIAL
    assert "cantilever_force_tip.mpm:46: note: fix(fEnd, force_nodes" in capsys.readouterr().err


def test_mpm_validate_and_run_take_a_karamelo_file(tmp_path, capsys):
    """Imported on the way: the notes and left-out lines on stderr, then as for a scene."""
    assert cli.main(["validate", str(DATA / "two-disks.mpm")]) == cli.EXIT_OK
    captured = capsys.readouterr()
    assert "valid 2D scene 'two-disks (imported from Karamelo)'" in captured.out
    assert "two-disks.mpm:38: not translated: dump(dump2, all, grid" in captured.err
    assert cli.main(["validate", str(DATA / "Vertical_bar__ULMPM__vertical_bar.mpm")]) == cli.EXIT_INVALID
    assert "cannot import the Karamelo file: line 34: solid(solid1, rectangle, ...) is old syntax" in \
        capsys.readouterr().err
    short = tmp_path / "disks.mpm"   # the two disks for 5 steps
    short.write_text((DATA / "two-disks.mpm").read_text().replace("run_time(3.5)", "run(5)"))
    assert cli.main(["run", str(short), "-o", str(tmp_path / "out"), "--progress", "none"]) == cli.EXIT_OK
    assert (tmp_path / "out" / "result.h5").exists()
    assert cli.main(["preview", str(tmp_path / "out" / "result.h5"), "--field", "von_mises",
                     "-o", str(tmp_path / "vm.png")]) == cli.EXIT_OK


def test_the_vortex_body_force_is_the_files_formula_by_name():
    """Karamelo's vortex body force through its fifteen variables (longer than an expression
    may be once written out) stays a few names long, and is the file's formula: here written
    again with numpy (x, y the reference position in tlmpm). The file's bt has +r (g' h)^2
    sin(alpha) where the vortex's acceleration gives -r (g' h)^2 sin(alpha)
    (examples/vortex_2d.json): the import keeps the file's formula, as Karamelo runs it."""
    translation = translate_file(DATA / "vortex__Linear__vortex.mpm")
    scene = load_scene(translation.scene)
    assert scene.body_force == ["bx_0", "by_0"] and max(map(len, scene.expressions.values())) < 200
    E, nu, rho0, Ro, Ri = 1e6, 0.3, 1050, 1.25, 0.75
    mdr, R = E / (2 * (1 + nu)) / rho0, (Ri + Ro) / 2
    rng = np.random.default_rng(5)
    radius, angle = rng.uniform(Ri, Ro, 40), rng.uniform(0, 2 * np.pi, 40)
    x, y = radius * np.cos(angle), radius * np.sin(angle)
    for t in (0.1, 0.37, 0.8):
        s = (radius - R) / (Ri - Ro)
        h = 1 - 8 * s**2 + 16 * s**4
        hp = -16 * (radius - R) / (Ri - Ro)**2 + 64 * (radius - R)**3 / (Ri - Ro)**4
        hpp = -16 / (Ri - Ro)**2 + 192 * (radius - R)**2 / (Ri - Ro)**4
        g, gp = np.sin(np.pi * t), np.pi * np.cos(np.pi * t)
        gpp, alpha = -np.pi**2 * g, g * h
        a = mdr * (3 * g * hp + radius * g * hpp) - radius * gpp * h
        br = a * np.sin(alpha) + (mdr * radius * (g * hp)**2 - radius * (gp * h)**2) * np.cos(alpha)
        bt = -a * np.cos(alpha) + (mdr * radius * (g * hp)**2 + radius * (gp * h)**2) * np.sin(alpha)
        expected = (br * np.cos(angle) - bt * np.sin(angle), br * np.sin(angle) + bt * np.cos(angle))
        for axis in range(2):
            got = scene.expression(scene.body_force[axis], ("X", "Y", "t")).evaluate(X=x, Y=y, t=t)
            assert np.allclose(got, expected[axis], rtol=1e-12, atol=1e-9 * np.max(np.abs(expected[axis])))


def test_the_vortex_dump_writes_the_reference_position(tmp_path):
    """The vortex dumps x0, y0, z0: imported as the `reference_position` field, nothing of
    that dump left untranslated, and a run writes each particle's seeded position there
    while its position moves."""
    from solver import run
    from solver.results import read_frame
    translation = translate_file(DATA / "vortex__Linear__vortex.mpm")
    assert "reference_position" in translation.scene["output"]["fields"]
    assert not any("x0" in item.reason for item in translation.untranslated)
    scene = dict(translation.scene, time={**translation.scene["time"], "end": 0.02}, output={
        **translation.scene["output"], "frames": 2})
    result = run(scene, tmp_path / "vortex")
    first, last = read_frame(result.result_path, 0)["fields"], read_frame(result.result_path, -1)["fields"]
    assert np.array_equal(first["reference_position"], first["position"])
    assert np.array_equal(last["reference_position"], first["position"])
    assert not np.array_equal(last["position"], first["position"])
