"""The client commands of ``mpm``: submit, jobs, status, cancel, download, delete, log, sweep.
Every command that takes a job id takes a unique start of it too.

Each command is registered by a ``register_*(subparsers)`` function, listed in the
``mpm.commands`` entry-point group; :func:`main` adds these and then every other
command of that group (the server package's run, validate, serve, ...), so the
``mpm`` script of either package offers all installed commands.
"""
from __future__ import annotations

import argparse
import functools
import json
import sys
import time
from datetime import datetime, timezone
from importlib.metadata import entry_points
from itertools import islice
from typing import Callable

from .client import Client, Job
from .errors import MpmError
from .models import STATUSES
from .progress import format_progress

Handler = Callable[[argparse.Namespace], int]
JobHandler = Callable[[argparse.Namespace, Job], int]


def _connection_options() -> argparse.ArgumentParser:
    """The options every client command takes (a parent parser)."""
    parent = argparse.ArgumentParser(add_help=False)
    group = parent.add_argument_group("service")
    group.add_argument("--server", metavar="URL", default=None,
                       help="service URL (default: $MPM_SERVER, else http://127.0.0.1:8000)")
    group.add_argument("--token", default=None, help="API token (default: $MPM_TOKEN)")
    return parent


def _client(args: argparse.Namespace) -> Client:
    return Client(args.server, token=args.token)


def _job_parser(subparsers: argparse._SubParsersAction, name: str, func: JobHandler,
                **parser_options: str) -> argparse.ArgumentParser:
    """The parser of a command about one job: the connection options and the job's id. The
    command runs ``func(args, job)`` with the job that the id names, its client open."""
    parser = subparsers.add_parser(name, parents=[_connection_options()], **parser_options)
    parser.add_argument("job_id", metavar="ID", help="a job id or a unique start of it")

    def run(args: argparse.Namespace) -> int:
        with _client(args) as client:
            return func(args, client.job(args.job_id))

    run.__name__ = name  # _reports_errors names the command in its messages by it
    parser.set_defaults(func=_reports_errors(run))
    return parser


def _reports_errors(handler: Handler) -> Handler:
    """Turn SDK errors into a message on stderr and exit status 1 (130 on Ctrl-C)."""

    command = handler.__name__.strip("_")

    @functools.wraps(handler)
    def run(args: argparse.Namespace) -> int:
        try:
            return handler(args)
        except (MpmError, OSError, ValueError, TypeError) as exc:
            print(f"mpm {command}: error: {exc}", file=sys.stderr)
            return 1
        except KeyboardInterrupt:
            print(f"mpm {command}: interrupted", file=sys.stderr)
            return 130

    return run


# -- submit ------------------------------------------------------------------------


def register_submit(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "submit", parents=[_connection_options()], help="submit a scene to the service",
        description="Submit a scene to the service; prints the job id on stdout.")
    parser.add_argument("scene", metavar="SCENE", help="scene file (JSON)")
    parser.add_argument("-n", "--processes", type=int, default=None, help="processes to ask for")
    parser.add_argument("--nodes", type=int, default=None,
                        help="Slurm nodes to spread the processes over (a service with MPM_LAUNCHER=slurm)")
    parser.add_argument("--wait", action="store_true", help="wait for the job to finish, with a progress bar")
    parser.add_argument("--download", metavar="FILE", default=None,
                        help="wait, then download result.h5 to FILE")
    parser.add_argument("--timeout", type=float, default=None, help="give up waiting after this many seconds")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress bar")
    parser.set_defaults(func=_submit)


@_reports_errors
def _submit(args: argparse.Namespace) -> int:
    with _client(args) as client:
        job = client.submit(args.scene, processes=args.processes, nodes=args.nodes)
        print(job.id, flush=True)
        if not (args.wait or args.download):
            return 0
        job.wait(timeout=args.timeout, progress=not args.quiet)
        if args.download:
            path = job.download(args.download)
            print(f"wrote {path}", file=sys.stderr)
    return 0


# -- jobs --------------------------------------------------------------------------


def register_jobs(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "jobs", parents=[_connection_options()], help="list your jobs, newest first")
    parser.add_argument("--status", choices=STATUSES, default=None, help="only jobs in this state")
    parser.add_argument("--limit", type=int, default=20, help="at most this many jobs (0: all; default 20)")
    parser.add_argument("--json", action="store_true", help="one JSON job record a line")
    parser.set_defaults(func=_jobs)


@_reports_errors
def _jobs(args: argparse.Namespace) -> int:
    with _client(args) as client:
        page_size = min(args.limit, 500) or None  # one request for the usual --limit; 0: the server's pages
        jobs = list(islice(client.jobs(status=args.status, limit=page_size), args.limit or None))
        if args.json:
            for job in jobs:
                print(job.record.model_dump_json())
            return 0
        print(_table(jobs))
    return 0


def _table(jobs: list[Job]) -> str:
    header = ("ID", "NAME", "STATUS", "PROGRESS", "SIM TIME", "AGE")
    rows = [header] + [
        (job.id[:8], job.record.name or "", job.record.status, f"{job.record.progress * 100:.0f}%",
         f"{job.record.sim_time:.4g}", _age(job.record.created_at))
        for job in jobs
    ]
    widths = [max(len(row[i]) for row in rows) for i in range(len(header))]
    return "\n".join("  ".join(cell.ljust(width) for cell, width in zip(row, widths)).rstrip() for row in rows)


def _age(created: datetime | None) -> str:
    """``"42 s"``, ``"5 min"``, ``"3 h"``, ``"2 d"``: how long ago the job was created."""
    if created is None:
        return ""
    if created.tzinfo is None:
        created = created.replace(tzinfo=timezone.utc)
    seconds = max(0, int((datetime.now(timezone.utc) - created).total_seconds()))
    for unit, size in (("d", 86400), ("h", 3600), ("min", 60)):
        if seconds >= size:
            return f"{seconds // size} {unit}"
    return f"{seconds} s"


# -- status ------------------------------------------------------------------------


def register_status(subparsers: argparse._SubParsersAction) -> None:
    parser = _job_parser(subparsers, "status", _status, help="show one job")
    parser.add_argument("--json", action="store_true", help="the whole job record as JSON")


def _status(args: argparse.Namespace, job: Job) -> int:
    record = job.record
    if args.json:
        print(json.dumps(record.model_dump(mode="json"), indent=2))
        return 0
    lines = [
        ("id", record.id), ("name", record.name or ""), ("status", record.status),
        ("progress", format_progress(record)), ("step", str(record.step)),
        ("created", str(record.created_at or "")), ("finished", str(record.finished_at or "")),
    ]
    energies = record.energies
    if energies.total is not None and energies.error is not None:
        lines.append(("energy", f"total {energies.total:.6g}, balance error {energies.error:.3g} "
                                f"(stored energy - work done on the bodies, against t = 0)"))
    if record.error:
        lines.append(("error", record.error))
    for key, value in lines:
        print(f"{key:>9}: {value}")
    return 0


# -- cancel ------------------------------------------------------------------------


def _job_action(name: str, act: Callable[[Job], str], help: str) -> Callable[[argparse._SubParsersAction], None]:
    """The ``register_*`` function of a command that does one thing to a job (``act``) and
    prints the line ``act`` returns."""

    def handler(args: argparse.Namespace, job: Job) -> int:
        print(act(job))
        return 0

    return lambda subparsers: _job_parser(subparsers, name, handler, help=help)


def _cancel(job: Job) -> str:
    return f"{job.id} {job.cancel().record.status}"


register_cancel = _job_action("cancel", _cancel, help="stop a job")


# -- download ----------------------------------------------------------------------


def register_download(subparsers: argparse._SubParsersAction) -> None:
    parser = _job_parser(subparsers, "download", _download, help="download a job's result.h5")
    parser.add_argument("file", metavar="FILE", help="where to write the HDF5 file")


def _download(args: argparse.Namespace, job: Job) -> int:
    path = job.download(args.file)
    print(f"wrote {path}", file=sys.stderr)
    return 0


# -- delete ------------------------------------------------------------------------


def _delete(job: Job) -> str:
    job.delete()
    return f"{job.id} deleted"


register_delete = _job_action("delete", _delete, help="remove a finished job and its files")


# -- log ---------------------------------------------------------------------------


def register_log(subparsers: argparse._SubParsersAction) -> None:
    parser = _job_parser(subparsers, "log", _log, help="print a job's solver log")
    parser.add_argument("--since", type=int, default=0, metavar="N", help="from line N on (0: the first)")
    parser.add_argument("-f", "--follow", action="store_true", help="keep printing new lines until the job ends")
    parser.add_argument("--poll", type=float, default=1.0, help="seconds between reads with --follow")


def _log(args: argparse.Namespace, job: Job) -> int:
    since = args.since
    while True:
        text, since = job.log(since)
        sys.stdout.write(text)
        sys.stdout.flush()
        if not args.follow or (not text and job.refresh().record.finished):
            return 0
        if not text:
            time.sleep(args.poll)


# -- sweep -------------------------------------------------------------------------


def _parameter(text: str) -> tuple[str, list]:
    """``/materials/m/youngs_modulus=1e6,2e6`` -> (pointer, [1000000.0, 2000000.0]); each
    value is read as JSON (a number, true, null, "text"), else kept as text."""
    pointer, sep, values = text.partition("=")
    if not sep or not pointer.startswith("/") or not values:
        raise argparse.ArgumentTypeError(f"expected POINTER=V1,V2,... with a JSON pointer (/a/b), got {text!r}")
    return pointer, [_value(item) for item in values.split(",")]


def _value(text: str):
    try:
        return json.loads(text)
    except ValueError:
        return text


def register_sweep(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "sweep", parents=[_connection_options()], help="submit one job per combination of parameter values",
        description="Submit a sweep: the scene once per combination of the values given to JSON pointers "
                    "into it; prints the sweep id, then (with --wait) a table of the jobs.")
    parser.add_argument("scene", metavar="SCENE", help="the base scene file (JSON)")
    parser.add_argument("-p", "--parameter", dest="parameters", action="append", type=_parameter, required=True,
                        metavar="POINTER=V1,V2", help="a JSON pointer into the scene and its values (repeat)")
    parser.add_argument("--mode", choices=("grid", "zip"), default="grid",
                        help="grid: every combination (default); zip: the lists side by side")
    parser.add_argument("--callback-url", default=None, help="POST the sweep there when it has finished")
    parser.add_argument("--wait", action="store_true", help="wait for every job, then print the table")
    parser.add_argument("-q", "--quiet", action="store_true", help="no progress line")
    parser.set_defaults(func=_sweep)


@_reports_errors
def _sweep(args: argparse.Namespace) -> int:
    with _client(args) as client:
        sweep = client.sweep(args.scene, dict(args.parameters), args.mode, callback_url=args.callback_url)
        print(sweep.id, flush=True)
        if args.wait:
            print(sweep.wait(progress=not args.quiet).table())
    return 0


# -- the mpm command ---------------------------------------------------------------

CLIENT_COMMANDS = (register_submit, register_jobs, register_status, register_cancel, register_download,
                   register_delete, register_log, register_sweep)


def add_plugin_commands(subparsers: argparse._SubParsersAction) -> None:
    """Add every ``mpm.commands`` entry point not already present; warn about those that fail to load."""
    for entry in sorted(entry_points(group="mpm.commands"), key=lambda e: e.name):
        if entry.name in subparsers.choices:
            continue
        try:
            entry.load()(subparsers)
        except Exception as exc:  # a broken or half-installed package must not take mpm down
            print(f"mpm: warning: command {entry.name!r} ({entry.value}) is unavailable: {exc}", file=sys.stderr)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="mpm", description="MPM simulations: run locally or through the service.")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND")
    for register in CLIENT_COMMANDS:
        register(subparsers)
    add_plugin_commands(subparsers)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if getattr(args, "func", None) is None:
        parser.print_help()
        return 2
    return int(args.func(args) or 0)


if __name__ == "__main__":
    sys.exit(main())
