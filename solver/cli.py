"""The ``mpm`` command line: run, validate, preview, examples, and sub-commands of other packages.

Other packages add sub-commands through the entry-point group ``mpm.commands``:
each entry point is ``register(subparsers) -> None``, which adds a parser and
``set_defaults(func=handler)``; ``handler(args)`` returns the exit code. They are
loaded only when the command line needs them (help, or one of their commands),
and one that fails to load is reported without breaking the others.

Exit codes of ``mpm run``: 0 complete, 2 invalid scene (every error printed as
``path: message`` on stderr), 3 the run ended early (unstable, cancelled,
max_steps: the diagnostic is printed on stderr).
"""
from __future__ import annotations

import argparse
import dataclasses
import json
import math
import numbers
import os
import signal
import sys
from importlib.metadata import entry_points
from pathlib import Path
from typing import Any, Callable

from solver.errors import SolverError
from solver.progress import ProgressBar, format_duration

ENTRY_POINT_GROUP = "mpm.commands"
EXIT_OK, EXIT_ERROR, EXIT_INVALID, EXIT_PARTIAL = 0, 1, 2, 3


# -- helpers -----------------------------------------------------------------


def _plain(obj: Any) -> dict[str, Any]:
    """A dataclass / pydantic model / dict as a JSON-ready dict (non-finite numbers -> null)."""
    if hasattr(obj, "model_dump"):
        data = obj.model_dump(mode="json")
    elif dataclasses.is_dataclass(obj):
        data = dataclasses.asdict(obj)
    else:
        data = dict(obj)

    def clean(value):
        if isinstance(value, dict):
            return {key: clean(item) for key, item in value.items()}
        if isinstance(value, (list, tuple)):
            return [clean(item) for item in value]
        if value is None or isinstance(value, (str, bool)):
            return value
        if isinstance(value, numbers.Integral):  # numpy integers too
            return int(value)
        if isinstance(value, numbers.Real):
            return float(value) if math.isfinite(value) else None
        return str(value)  # paths

    return clean(data)


def _print_scene_errors(source: str, error) -> None:
    errors = error.errors
    print(f"mpm: {source}: {len(errors)} validation error(s)", file=sys.stderr)
    for item in errors:
        print(f"{item['path'] or '(scene)'}: {item['message']}", file=sys.stderr)


def _load(path: str | dict, processes: int | None = None, threads: int | None = None):
    """The validated scene of a file (or a scene document), with ``parallel.processes``
    and ``parallel.threads`` overridden where given; None after printing errors."""
    from solver.scene import SceneError
    from solver.scene_checks import load_scene

    # a local command: a checkpoint's scene may read its files too (their names were made absolute)
    files = Path.cwd() if isinstance(path, dict) else Path(path).resolve().parent
    source = path if isinstance(path, dict) else Path(path)
    if is_karamelo(path):
        source = _imported(path)
        if source is None:
            return None
    try:
        scene = load_scene(source, files=files)
        given = {k: v for k, v in (("processes", processes), ("threads", threads)) if v is not None}
        if given:
            data = scene.model_dump(mode="json")
            data["parallel"] = {**(data.get("parallel") or {}), **given}
            scene = load_scene(data, files=files)
    except SceneError as error:
        _print_scene_errors("the checkpoint's scene" if isinstance(path, dict) else path, error)
        return None
    return scene


def is_karamelo(path: Any) -> bool:
    """A Karamelo input file (`.mpm`): run and validate import it on the way."""
    return isinstance(path, (str, Path)) and str(path).lower().endswith(".mpm")


def _imported(path: str | Path) -> dict | None:
    """The scene of a Karamelo file, its notes and left-out lines on stderr; None after
    printing why the file cannot be imported."""
    from solver.karamelo import KarameloError, translate_file

    try:
        translation = translate_file(path)
    except (OSError, UnicodeDecodeError, KarameloError) as error:
        print(f"mpm: {path}: cannot import the Karamelo file: {error}", file=sys.stderr)
        return None
    _print_translation(str(path), translation)
    return translation.scene


def human_bytes(count: float) -> str:
    for unit in ("B", "KiB", "MiB", "GiB", "TiB"):
        if abs(count) < 1024 or unit == "TiB":
            return f"{count:.0f} {unit}" if unit == "B" else f"{count:.1f} {unit}"
        count /= 1024
    raise AssertionError("unreachable")


def human_seconds(seconds: float) -> str:
    return f"{seconds:.2g} s" if seconds < 60 else format_duration(seconds)


def _positive_int(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be >= 1, got {value}")
    return value


# -- mpm run -----------------------------------------------------------------


def register_run(subparsers) -> None:
    parser = subparsers.add_parser(
        "run", help="run a scene locally (no server)",
        description="Run a scene here and write result.h5, result.xdmf and preview.png.",
    )
    parser.add_argument("scene", nargs="?", help="scene file (JSON, or a Karamelo .mpm file, imported on the way); "
                                                 "with --resume: the checkpoint's by default")
    parser.add_argument("-o", "--output", metavar="DIR", help="output folder (default: out/<scene file name>)")
    parser.add_argument("-n", "--processes", type=_positive_int, metavar="K",
                        help="processes to run on (sets parallel.processes)")
    parser.add_argument("-t", "--threads", type=_positive_int, metavar="T",
                        help="threads per process (sets parallel.threads; default: the cores, shared)")
    parser.add_argument("--resume", metavar="DIR",
                        help="continue the run in DIR from its checkpoint (from the start when it has none)")
    parser.add_argument("--checkpoint-seconds", type=float, metavar="S",
                        help="a restart checkpoint every S seconds of wall time (default 60; "
                             "the scene's output.checkpoint wins)")
    parser.add_argument("--progress", choices=("bar", "json", "none"), default="bar",
                        help="bar: a progress line; json: one JSON object per update (for programs); none")
    parser.set_defaults(func=cmd_run)


def _run_target(scene: str | None, output: str | None, resume: str | None) -> tuple[str | dict, Path]:
    """`mpm run [SCENE] [-o DIR] [--resume DIR]`: the scene to load and the output folder."""
    if resume is None:
        if scene is None:
            raise ValueError("give a scene file (or --resume DIR)")
        return scene, Path(output) if output else Path("out") / Path(scene).stem
    if output and Path(output).resolve() != Path(resume).resolve():
        raise ValueError("--resume DIR continues the run in DIR: -o, when given, must name the same folder")
    if scene is None:
        from solver.checkpoint import scene_of
        return json.loads(scene_of(resume)), Path(resume)
    return scene, Path(resume)


def cmd_run(args: argparse.Namespace) -> int:
    try:
        scene_source, out_dir = _run_target(args.scene, args.output, args.resume)
    except ValueError as error:
        print(f"mpm run: error: {error}", file=sys.stderr)
        return EXIT_ERROR
    scene = _load(scene_source, args.processes, args.threads)
    if scene is None:
        return EXIT_INVALID
    from solver import parallel

    if scene.parallel.processes > 1 and parallel.launch.world() is None:
        _exec_processes(scene.parallel.processes, args)   # becomes mpiexec: does not return
    from solver import run  # numba and the kernels load only for a run

    if not parallel.is_root():   # with several processes rank 0 reports, the others compute
        result = run(scene, out_dir, resume=args.resume is not None, checkpoint_seconds=args.checkpoint_seconds)
        _ignore_stop_signals()
        parallel.all_ranks_done()   # (rank 0 has reported: EXIT_PARTIAL here makes mpiexec stop it)
        return EXIT_OK if result.status == "complete" else EXIT_PARTIAL

    progress: Callable[[Any], None] | None = None
    bar = ProgressBar() if args.progress == "bar" else None
    if bar is not None:
        progress = bar.update
    elif args.progress == "json":
        def progress(info: Any) -> None:
            try:
                print(json.dumps({"event": "progress", **_plain(info)}), flush=True)
            except BrokenPipeError:  # the reader died (a killed worker): run on to its stop signal
                os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())

    try:
        result = run(scene, out_dir, progress=progress, resume=args.resume is not None,
                     checkpoint_seconds=args.checkpoint_seconds)
    except SolverError as error:  # a checkpoint of another scene
        print(f"mpm run: error: {error}", file=sys.stderr)
        return EXIT_ERROR
    _ignore_stop_signals()
    if bar is not None:
        bar.close()
    done = _plain(result)
    if args.progress == "json":
        print(json.dumps({"event": "done", **done}), flush=True)
    else:
        print(
            f"{done['status']}: {done['steps']} steps, t = {done['time']:.6g} "
            f"in {human_seconds(done['wall_seconds'])} -> {done['result_path']}"
        )
        balance = _balance_line(done["result_path"])
        if balance:
            print(balance)
    parallel.all_ranks_done()
    if done["status"] == "complete":
        return EXIT_OK
    print(f"mpm run: the run ended early ({done['reason']}): {done['message']}", file=sys.stderr)
    return EXIT_PARTIAL


def _balance_line(result_path: str) -> str | None:
    """'energy balance: ...' from the result's series (solver/energy.py), None without energies."""
    import numpy as np

    from solver.results import read_series

    try:
        series = read_series(result_path)
    except (OSError, KeyError, ValueError):
        return None
    if len(series.get("energy_error", ())) == 0:
        return None
    error = float(series["energy_error"][-1])
    scale = max(float(np.nanmax(np.abs(series[name]))) for name in ("total_energy", "external_work", "boundary_work")
                if name in series)
    share = f" ({100 * abs(error) / scale:.3g} % of the largest energy)" if scale > 0 else ""
    dissipated = " + plastic work" if "plastic_work" in series else ""
    return (f"energy balance: total {float(series['total_energy'][-1]):.6g}, "
            f"error {error:.3g}{share} (stored energy{dissipated} - work done on the bodies, against t = 0)")


def _ignore_stop_signals() -> None:
    """From the run's end to the exit: the run has saved what it had, so a stop signal has nothing
    left to stop, and would kill a rank that waits for rank 0 to report (Slurm signals a preempted
    job's processes node by node and more than once; MPI's launcher then aborts every rank)."""
    for sig in (signal.SIGTERM, signal.SIGINT):
        signal.signal(sig, signal.SIG_IGN)


def _exec_processes(processes: int, args: argparse.Namespace) -> None:
    """Replace this process by `mpiexec -n K` running the same command in each rank
    (same pid: a signal to this process reaches mpiexec, which forwards it to the ranks)."""
    from solver.parallel import launch

    given = [args.scene] if args.scene else []
    given += ["-o", args.output] if args.output else []
    given += ["--resume", args.resume] if args.resume else []
    given += ["--checkpoint-seconds", repr(args.checkpoint_seconds)] if args.checkpoint_seconds else []
    given += ["-t", str(args.threads)] if args.threads else []
    command = launch.command(processes, ["run", *given, "-n", str(processes), "--progress", args.progress])
    sys.stdout.flush()
    sys.stderr.flush()
    os.execve(command[0], command, launch.environment())


# -- mpm validate ------------------------------------------------------------


def register_validate(subparsers) -> None:
    parser = subparsers.add_parser(
        "validate", help="check a scene and print what it will cost",
        description="Validate a scene; print its particles, grid nodes, steps, memory and run time, "
                    "or every error with its path.",
    )
    parser.add_argument("scene", help="scene file (JSON, or a Karamelo .mpm file, imported on the way)")
    parser.set_defaults(func=cmd_validate)


def cmd_validate(args: argparse.Namespace) -> int:
    from solver.scene import SceneError
    from solver.scene_checks import MACHINE_LIMITS, load_scene

    scene = _load(args.scene)
    if scene is None:
        return EXIT_INVALID
    try:
        load_scene(scene, limits=MACHINE_LIMITS)
    except SceneError as error:
        _print_scene_errors(args.scene, error)
        return EXIT_INVALID
    from solver.summary import summarize

    summary = summarize(scene)
    bodies = ", ".join(
        f"{body.name} {count:,}" for body, count in zip(scene.bodies, summary.particles_per_body)
    )
    rows = [
        ("particles", f"{summary.particles:,}  ({bodies})"),
        ("method", _method_line(scene.method)),
        *_gas_density_rows(scene),
        ("grid nodes", f"{summary.grid_nodes:,}  ({' x '.join(map(str, summary.grid_shape))} cells)"),
        ("time step", f"{summary.dt:.6g}" + ("" if scene.time.dt else "  (adaptive, estimated)")),
        ("estimated steps", f"{summary.estimated_steps:,}"),
        ("memory", human_bytes(summary.memory_bytes)),
        ("estimated run time", human_seconds(summary.estimated_run_seconds) + f"  ({_cost_model_source()})"),
    ]
    print(f"{args.scene}: valid {scene.dimension}D scene {scene.name!r}")
    for label, value in rows:
        print(f"  {label:<20}{value}")
    for warning in summary.warnings:
        print(f"  warning: {warning['path']}: {warning['message']}")
    return EXIT_OK


def _gas_density_rows(scene) -> list[tuple[str, str]]:
    """How each ideal gas's density is taken (solver/gas_density.py), its default resolved."""
    from solver.materials.ideal_gas import takes_grid_density

    return [(f"gas {name}", "density from the grid" if takes_grid_density(scene, material)
             else "density from its own volumes (J V0)")
            for name, material in scene.materials.items() if material.model == "ideal_gas"]


def _method_line(method) -> str:
    """The scheme, shape function and transfer the run will use, the defaults resolved
    (a material's own default included: Scene._material_method_defaults)."""
    return f"{method.formulation} {method.scheme}, {method.shape_function}, {method.transfer}"


def _cost_model_source() -> str:
    from solver import cost

    source = cost.load_model().source
    return "this machine's calibration" if source != str(cost.SHIPPED) else "shipped cost model; mpm calibrate measures this machine"


# -- mpm preview -------------------------------------------------------------


def register_preview(subparsers) -> None:
    parser = subparsers.add_parser(
        "preview", help="render a frame of a result file as PNG",
        description="Render one frame of result.h5, particles coloured by a field.",
    )
    parser.add_argument("result", help="result file (result.h5)")
    parser.add_argument("--frame", type=int, default=-1, help="frame index; negative counts from the end (default -1)")
    parser.add_argument("--field", help="field to colour by (default: the scene's preview field)")
    parser.add_argument("-o", "--output", metavar="PNG",
                        help="image file (default: preview-<frame>[-<field>].png beside the result)")
    parser.set_defaults(func=cmd_preview)


def cmd_preview(args: argparse.Namespace) -> int:
    from solver.preview import render_preview

    result = Path(args.result)
    if args.output:
        out = Path(args.output)
    else:
        frame = "last" if args.frame == -1 else str(args.frame)
        out = result.parent / f"preview-{frame}{'-' + args.field if args.field else ''}.png"
    return _drawn("preview", out, lambda: render_preview(result, frame=args.frame, field=args.field, out=out))


def _drawn(command: str, out: Path, draw) -> int:
    """Run `draw` (it writes `out`) and print the file's path; a result it cannot read is an error
    line naming the command."""
    try:
        draw()
    except (OSError, ValueError, IndexError) as error:
        print(f"mpm {command}: error: {error}", file=sys.stderr)
        return EXIT_ERROR
    print(out)
    return EXIT_OK


# -- mpm animate -------------------------------------------------------------


def register_animate(subparsers) -> None:
    parser = subparsers.add_parser(
        "animate", help="write every frame of a result file as a GIF or MP4 animation",
        description="Draw every frame of result.h5 as the previews are, with one colour scale for the "
                    "whole run, and encode them as a GIF or an MP4 (H.264), chosen by the file's suffix.",
    )
    parser.add_argument("result", help="result file (result.h5)")
    parser.add_argument("-o", "--output", metavar="FILE",
                        help="run.gif or run.mp4 (default: animation.gif beside the result)")
    parser.add_argument("--field", help="field to colour by (default: the scene's preview field)")
    parser.add_argument("--fps", type=float, default=None, help="frames per second (default 10)")
    parser.set_defaults(func=cmd_animate)


def cmd_animate(args: argparse.Namespace) -> int:
    from solver.animation import DEFAULT_FPS, render_animation

    result = Path(args.result)
    out = Path(args.output) if args.output else result.parent / "animation.gif"
    return _drawn("animate", out, lambda: render_animation(result, out, field=args.field, fps=args.fps or DEFAULT_FPS))


# -- mpm examples ------------------------------------------------------------


def register_examples(subparsers) -> None:
    parser = subparsers.add_parser(
        "examples", help="list the built-in example scenes, or print one",
        description="Without NAME: list the examples. With NAME: print that scene as JSON "
                    "(mpm examples two_disks > two_disks.json).",
    )
    parser.add_argument("name", nargs="?", help="example to print")
    parser.set_defaults(func=cmd_examples)


def cmd_examples(args: argparse.Namespace) -> int:
    from solver.examples import ExampleNotFound, list_examples, load_example

    if args.name:
        try:
            print(json.dumps(load_example(args.name), indent=2))
        except ExampleNotFound as error:
            print(f"mpm examples: error: {error}", file=sys.stderr)
            return EXIT_ERROR
        return EXIT_OK
    examples = list_examples()
    width = max((len(example["name"]) for example in examples), default=4)
    print(f"{'NAME':<{width}}  DIM  TITLE")
    for example in examples:
        print(f"{example['name']:<{width}}  {example['dimension']}D   {example['title']}")
    return EXIT_OK


# -- mpm import ----------------------------------------------------------------


def register_import(subparsers) -> None:
    parser = subparsers.add_parser(
        "import", help="translate another code's input file into a scene",
        description="Translate a Karamelo input file into a scene (JSON). Every line that has no "
                    "translation is listed on stderr with its number and the reason; nothing is guessed. "
                    "Exit 0: all translated and the scene is valid; 3: lines left out, the scene valid; "
                    "2: the scene is not valid (written anyway, to finish by hand); 1: the file cannot be read.",
    )
    parser.add_argument("format", choices=["karamelo"], help="the input file's code")
    parser.add_argument("file", help="the input file (.mpm)")
    parser.add_argument("-o", "--output", metavar="SCENE", help="scene file to write (default: stdout)")
    parser.set_defaults(func=cmd_import)


def cmd_import(args: argparse.Namespace) -> int:
    from solver.karamelo import KarameloError, translate_file
    from solver.scene import SceneError
    from solver.scene_checks import load_scene

    try:
        translation = translate_file(args.file)
    except (OSError, UnicodeDecodeError, KarameloError) as error:
        print(f"mpm import: {args.file}: {error}", file=sys.stderr)
        return EXIT_ERROR
    text = json.dumps(translation.scene, indent=2) + "\n"
    if args.output:
        Path(args.output).write_text(text, encoding="utf-8")
    else:
        sys.stdout.write(text)
    _print_translation(args.file, translation)
    try:
        load_scene(translation.scene)
    except SceneError as error:
        _print_scene_errors(args.output or "the translated scene", error)
        return EXIT_INVALID
    return EXIT_PARTIAL if translation.untranslated else EXIT_OK


def _print_translation(source: str, translation) -> None:
    """Every line that is not translated, and every note on a translated one, on stderr."""
    for item in translation.notes:
        print(f"{source}:{item.line}: note: {item.text}: {item.reason}" if item.text
              else f"{source}:{item.line}: note: {item.reason}", file=sys.stderr)
    for item in translation.untranslated:
        print(f"{source}:{item.line}: not translated: {item.text}: {item.reason}" if item.text
              else f"{source}:{item.line}: {item.reason}", file=sys.stderr)


# -- mpm calibrate -----------------------------------------------------------


def register_calibrate(subparsers) -> None:
    parser = subparsers.add_parser(
        "calibrate", help="measure this machine's speed for the run-time estimates",
        description="Time small blocks of every kind of step (a few minutes) and store the cost model "
                    "that `mpm validate` and the service's estimates use (solver/cost.py).",
    )
    parser.add_argument("-o", "--output", metavar="JSON",
                        help="where to store it (default: cost_model.json in the user's cache folder, mpm-solver/)")
    parser.set_defaults(func=cmd_calibrate)


def cmd_calibrate(args: argparse.Namespace) -> int:
    from solver.calibrate import calibrate, save

    model = calibrate(log=lambda line: print(line, flush=True))
    print(f"stored in {save(model, Path(args.output) if args.output else None)}")
    return EXIT_OK


# -- the command -------------------------------------------------------------

BUILTINS = {
    "run": register_run,
    "validate": register_validate,
    "preview": register_preview,
    "animate": register_animate,
    "examples": register_examples,
    "import": register_import,
    "calibrate": register_calibrate,
}


def _load_plugins(subparsers, only: str | None) -> None:
    """Add the sub-commands of the entry-point group (``only``: just that one when it exists)."""
    plugins = [ep for ep in entry_points(group=ENTRY_POINT_GROUP) if ep.name not in subparsers.choices]
    if only is not None and any(ep.name == only for ep in plugins):
        plugins = [ep for ep in plugins if ep.name == only]
    for ep in sorted(plugins, key=lambda ep: ep.name):
        if ep.name in subparsers.choices:  # an installed package declared it twice
            continue
        try:
            ep.load()(subparsers)
        except Exception as error:  # a broken plugin must not break the other commands
            print(
                f"mpm: warning: command {ep.name!r} is unavailable ({ep.value}): "
                f"{type(error).__name__}: {error}",
                file=sys.stderr,
            )


def build_parser(argv: list[str]) -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="mpm", description="Material point method simulations: run, validate, preview, serve.",
    )
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for register in BUILTINS.values():
        register(subparsers)
    command = next((arg for arg in argv if not arg.startswith("-")), None)
    if command not in BUILTINS:
        _load_plugins(subparsers, only=command)
    return parser


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    parser = build_parser(argv)
    args = parser.parse_args(argv)
    if getattr(args, "func", None) is None:
        parser.print_help(sys.stderr)
        return EXIT_INVALID
    return int(args.func(args) or 0)
