"""The mpm command line and its progress bar."""
import io
import json
import subprocess
import sys
from pathlib import Path

import pytest

from solver import cli
from solver.examples import list_examples
from solver.progress import ProgressBar, format_duration

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def tiny_bar(**time) -> dict:
    """The E1 bar, run for a short time (a few dozen steps)."""
    scene = json.loads((EXAMPLES / "bar_vibration.json").read_text())
    scene["time"] = {"end": 0.5, "dt": 0.015625, **time}
    scene["output"]["frames"] = 3
    return scene


def scene_file(tmp_path, scene: dict, name="scene.json") -> str:
    path = tmp_path / name
    path.write_text(json.dumps(scene))
    return str(path)


# -- validate ------------------------------------------------------------------------


def test_validate_prints_the_summary(capsys):
    assert cli.main(["validate", str(EXAMPLES / "two_disks.json")]) == 0
    out = capsys.readouterr().out
    assert "valid 2D scene" in out
    assert "416  (disk1 208, disk2 208)" in out   # E2: 416 particles
    assert "441  (20 x 20 cells)" in out
    assert "estimated steps     3,500" in out
    assert "memory" in out and "MiB" in out   # the run's peak, with the process baseline
    assert "estimated run time" in out


def test_validate_prints_the_method_with_a_material_s_default(tmp_path, capsys):
    """The ideal gas's shape function default (Scene._material_method_defaults) is shown as resolved."""
    scene = json.loads((EXAMPLES / "sod_shock_tube.json").read_text())
    del scene["method"]
    assert cli.main(["validate", scene_file(tmp_path, scene)]) == 0
    assert "method              ulmpm musl, cubic_bspline, flip" in capsys.readouterr().out
    assert cli.main(["validate", str(EXAMPLES / "two_disks.json")]) == 0
    assert "method              ulmpm musl, linear, flip" in capsys.readouterr().out


def test_validate_says_how_a_gas_takes_its_density(tmp_path, capsys):
    """density_from_grid's default resolved: from the grid where the shape function has nodal
    integrals (cubic B-splines), the particles' own volumes where it has not (GIMP)."""
    scene = json.loads((EXAMPLES / "sod_shock_tube.json").read_text())
    assert cli.main(["validate", scene_file(tmp_path, scene)]) == 0
    assert f"{'gas air':<20}density from the grid" in capsys.readouterr().out
    scene["method"]["shape_function"] = "gimp"
    assert cli.main(["validate", scene_file(tmp_path, scene)]) == 0
    assert f"{'gas air':<20}density from its own volumes (J V0)" in capsys.readouterr().out
    assert cli.main(["validate", str(EXAMPLES / "two_disks.json")]) == 0
    assert "gas " not in capsys.readouterr().out


def test_validate_prints_every_error_with_its_path(tmp_path, capsys):
    scene = json.loads((EXAMPLES / "two_disks.json").read_text())
    scene["bodies"][1]["geometry"]["radius"] = -0.2
    scene["materials"]["elastic"]["poisson_ratio"] = 0.7
    scene["time"]["end"] = 0
    assert cli.main(["validate", scene_file(tmp_path, scene)]) == 2
    err = capsys.readouterr().err
    assert "3 validation error(s)" in err
    for path in ("bodies[1].geometry.radius: ", "materials.elastic.poisson_ratio: ", "time.end: "):
        assert any(line.startswith(path) for line in err.splitlines()), path


def test_validate_a_missing_file(tmp_path, capsys):
    assert cli.main(["validate", str(tmp_path / "nope.json")]) == 2
    assert "nope.json" in capsys.readouterr().err


# -- examples ------------------------------------------------------------------------


def test_examples_lists_every_example(capsys):
    assert cli.main(["examples"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split() == ["NAME", "DIM", "TITLE"]
    listed = {line.split()[0]: line.split()[1] for line in lines[1:]}
    assert listed == {e["name"]: f"{e['dimension']}D" for e in list_examples()}
    assert {"two_disks", "bar_vibration", "elastic_cube_3d"} <= set(listed)


def test_examples_prints_one_as_json(capsys):
    assert cli.main(["examples", "two_disks"]) == 0
    assert json.loads(capsys.readouterr().out) == json.loads((EXAMPLES / "two_disks.json").read_text())


def test_examples_unknown_name(capsys):
    assert cli.main(["examples", "../pyproject"]) == 1
    assert "two_disks" in capsys.readouterr().err  # lists what there is


# -- preview -------------------------------------------------------------------------


@pytest.fixture(scope="module")
def bar_result(tmp_path_factory):
    out = tmp_path_factory.mktemp("bar")
    assert cli.main(["run", scene_file(out, tiny_bar()), "-o", str(out), "--progress", "none"]) == 0
    return out / "result.h5"


def test_preview_writes_beside_the_result_by_default(bar_result, capsys):
    assert cli.main(["preview", str(bar_result), "--frame", "1", "--field", "stress"]) == 0
    written = Path(capsys.readouterr().out.strip())
    assert written == bar_result.parent / "preview-1-stress.png"
    assert written.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_preview_to_a_file(bar_result, tmp_path, capsys):
    assert cli.main(["preview", str(bar_result), "-o", str(tmp_path / "p.png")]) == 0
    assert (tmp_path / "p.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("args, message", [
    (["--field", "temperature"], "'temperature' is not in this frame"),
    (["--frame", "9"], "out of range"),
])
def test_preview_errors(bar_result, tmp_path, capsys, args, message):
    assert cli.main(["preview", str(bar_result), "-o", str(tmp_path / "p.png"), *args]) == 1
    assert message in capsys.readouterr().err


def test_preview_of_a_missing_file(tmp_path, capsys):
    assert cli.main(["preview", str(tmp_path / "result.h5")]) == 1
    assert "result.h5" in capsys.readouterr().err


# -- run -----------------------------------------------------------------------------


def test_run_json_progress_end_to_end(tmp_path):
    """What the worker does: python -m solver run ... --progress json, one JSON object per line."""
    out = tmp_path / "out"
    done = subprocess.run(
        [sys.executable, "-m", "solver", "run", scene_file(tmp_path, tiny_bar()), "-o", str(out),
         "--progress", "json"],
        capture_output=True, text=True, timeout=300,
    )
    assert done.returncode == 0, done.stderr
    lines = [json.loads(line) for line in done.stdout.splitlines()]
    assert {line["event"] for line in lines[:-1]} == {"progress"}
    assert set(lines[0]) == {"event", "step", "time", "end_time", "fraction", "steps_per_second",
                             "eta_seconds", "dt", "energies", "stage"}
    stages = [line["stage"] for line in lines[:-1]]   # in order: each stage once, none skipped
    assert sorted(set(stages), key=stages.index) == ["compiling", "stepping", "writing"]
    assert lines[-2]["fraction"] == pytest.approx(1.0)
    final = lines[-1]
    assert final["event"] == "done" and final["compiled"] >= 0 and final["compile_seconds"] >= 0
    assert (final["status"], final["reason"], final["steps"]) == ("complete", "finished", 32)
    assert final["result_path"] == str(out / "result.h5")
    for name in ("result.h5", "result.xdmf", "preview.png"):
        assert (out / name).is_file(), name


def test_run_with_a_bar_into_the_default_folder(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert cli.main(["run", scene_file(tmp_path, tiny_bar(), "bar.json")]) == 0
    out = capsys.readouterr().out
    assert "100.0%" in out and "complete: 32 steps" in out
    assert (tmp_path / "out" / "bar" / "result.h5").is_file()
    # the energy balance's error, as in the series (FLIP 1.0 on the E1 bar: a small share of its energy)
    from solver.results import read_series
    series = read_series(tmp_path / "out" / "bar" / "result.h5")
    assert f"energy balance: total {series['total_energy'][-1]:.6g}, error {series['energy_error'][-1]:.3g}" in out


def test_run_that_becomes_unstable_exits_3_with_the_diagnostic(tmp_path, capsys):
    scene = tiny_bar(end=20.0, dt=1.0, allow_unstable_dt=True)  # CFL 6.4: validation would refuse it
    code = cli.main(["run", scene_file(tmp_path, scene), "-o", str(tmp_path / "o"), "--progress", "none"])
    assert code == 3
    err = capsys.readouterr().err
    assert "(unstable)" in err and "step" in err


def test_run_rejects_an_invalid_scene_with_exit_2(tmp_path, capsys):
    scene = tiny_bar()
    scene["bodies"][0]["material"] = "steel"
    assert cli.main(["run", scene_file(tmp_path, scene), "-o", str(tmp_path / "o")]) == 2
    assert "bodies[0].material: unknown material 'steel'" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_run_passes_processes_to_the_scene(tmp_path, capsys):
    # -n sets parallel.processes, which validation checks (the cap of the solver)
    assert cli.main(["run", scene_file(tmp_path, tiny_bar()), "-n", "65", "-o", str(tmp_path / "o")]) == 2
    assert "parallel.processes: 65 processes is not supported yet (at most 64)" in capsys.readouterr().err


# -- sub-commands of other packages --------------------------------------------------


class FakeEntryPoint:
    def __init__(self, name, register=None, error=None):
        self.name, self.value = name, f"fake.module:register_{name}"
        self._register, self._error = register, error
        self.loaded = False

    def load(self):
        self.loaded = True
        if self._error:
            raise self._error
        return self._register


def hello_register(subparsers):
    parser = subparsers.add_parser("hello", help="say hello")
    parser.add_argument("--code", type=int, default=7)
    parser.set_defaults(func=lambda args: args.code)


@pytest.fixture
def plugins(monkeypatch):
    points = [
        FakeEntryPoint("hello", hello_register),
        FakeEntryPoint("broken", error=ModuleNotFoundError("No module named 'fake'")),
        FakeEntryPoint("run", cli.register_run),  # declared in pyproject too: the built-in wins
    ]
    monkeypatch.setattr(cli, "entry_points", lambda group: points if group == "mpm.commands" else [])
    return {point.name: point for point in points}


def test_plugin_commands_run_and_a_broken_one_only_warns(plugins, capsys):
    assert cli.main(["hello", "--code", "5"]) == 5
    assert plugins["hello"].loaded and not plugins["broken"].loaded  # only the one asked for
    with pytest.raises(SystemExit) as exit_:
        cli.main(["--help"])
    assert exit_.value.code == 0
    captured = capsys.readouterr()
    assert "say hello" in captured.out
    assert "warning: command 'broken' is unavailable (fake.module:register_broken)" in captured.err
    assert "No module named 'fake'" in captured.err
    assert not plugins["run"].loaded


def test_builtin_commands_do_not_load_plugins(plugins, capsys):
    assert cli.main(["examples"]) == 0
    assert not any(point.loaded for point in plugins.values())
    assert "warning" not in capsys.readouterr().err


def test_no_command_prints_help(plugins, capsys):
    assert cli.main([]) == 2
    assert "run" in capsys.readouterr().err


def test_the_installed_entry_points_name_existing_functions():
    from importlib.metadata import entry_points

    for point in entry_points(group="mpm.commands"):
        if point.module == "solver.cli":
            assert callable(point.load())


# -- progress bar --------------------------------------------------------------------


class Clock:
    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now


class Terminal(io.StringIO):
    def isatty(self):
        return True


def info(step, fraction=None):
    fraction = step / 100 if fraction is None else fraction
    return {"step": step, "time": fraction * 2.0, "end_time": 2.0, "fraction": fraction,
            "steps_per_second": 250.0, "eta_seconds": 75.0 * (1 - fraction)}


def test_bar_redraws_in_place_at_most_four_times_a_second():
    clock, stream = Clock(), Terminal()
    bar = ProgressBar(stream, clock=clock)
    for step in range(1, 11):  # 10 updates in 0.45 s
        bar.update(info(step))
        clock.now += 0.05
    bar.update(info(100))
    bar.close()
    text = stream.getvalue()
    draws = text.split("\r")[1:]
    assert len(draws) == 3  # t = 0, t = 0.25, and the last state at close
    assert "  1.0%  step 1 " in draws[0] and "[" in draws[0]
    assert "100.0%  step 100  t 2/2  250 steps/s  ETA 0:00" in draws[-1]
    assert text.endswith("\n") and text.count("\n") == 1


def test_plain_lines_every_few_seconds_when_not_a_terminal():
    clock, stream = Clock(), io.StringIO()
    bar = ProgressBar(stream, plain_interval=5.0, clock=clock)
    for step in range(0, 101, 10):  # one update a second
        bar.update(info(step))
        clock.now += 1.0
    bar.close()
    lines = stream.getvalue().splitlines()
    assert [line.split()[2] for line in lines] == ["0", "50", "100"]
    assert "\r" not in stream.getvalue() and "[" not in stream.getvalue()


def test_durations():
    assert [format_duration(s) for s in (0, 75, 3725, None, float("inf"))] == ["0:00", "1:15", "1:02:05", "?", "?"]
