"""The sub-commands that other packages add to `mpm` through the entry-point group
`mpm.commands` (solver/cli.py): `mpm serve` (service/cli.py) and `mpm worker` (worker/cli.py)."""
from __future__ import annotations

import argparse
from typing import Any, Callable


def subcommand(name: str, add_arguments: Callable[[argparse.ArgumentParser], None],
               command: Callable[[argparse.Namespace], int], *, help: str,
               description: str) -> Callable[[Any], None]:
    """The entry point of the sub-command ``name``: it adds ``name`` to `mpm`'s sub-parsers
    with the options of ``add_arguments`` (which `python -m worker` also uses), run by ``command``."""

    def register(subparsers: Any) -> None:
        parser = subparsers.add_parser(name, help=help, description=description)
        add_arguments(parser)
        parser.set_defaults(func=command)

    return register
