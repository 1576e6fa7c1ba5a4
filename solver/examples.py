"""The built-in example scenes: the JSON files of ``examples/`` at the repository root.

An example's name is its file stem (``two_disks``), its title the scene's
``name`` field. ``MPM_EXAMPLES_DIR`` points to another folder.
"""
from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from solver.errors import SolverError

DEFAULT_DIR = Path(__file__).resolve().parent.parent / "examples"


class ExampleNotFound(SolverError, KeyError):
    """No example of that name (the message lists the ones there are)."""

    def __str__(self) -> str:  # KeyError would print the message quoted
        return str(self.args[0])


def examples_dir() -> Path:
    return Path(os.environ.get("MPM_EXAMPLES_DIR") or DEFAULT_DIR)


def _read(path: Path) -> dict[str, Any]:
    try:
        return json.loads(path.read_text(encoding="utf-8"))
    except json.JSONDecodeError as error:
        raise ValueError(f"example {path} is not valid JSON: {error}") from error


def list_examples() -> list[dict[str, Any]]:
    """``[{"name", "title", "dimension", "path"}]``, sorted by name."""
    examples = []
    for path in sorted(examples_dir().glob("*.json")):
        scene = _read(path)
        examples.append({
            "name": path.stem,
            "title": scene.get("name") or path.stem,
            "dimension": scene.get("dimension"),
            "path": str(path),
        })
    return examples


def load_example(name: str) -> dict[str, Any]:
    """The scene document of one example, its mesh files inlined as data (a document
    the service accepts: it never opens a path named in a scene).

    Only names from :func:`list_examples` are accepted, so a name can never
    reach outside the examples folder.
    """
    known = {example["name"]: example for example in list_examples()}
    if name not in known:
        raise ExampleNotFound(
            f"no example named {name!r}; available: {', '.join(sorted(known)) or 'none'}"
        )
    from solver.mesh import inline_files

    path = Path(known[name]["path"])
    return inline_files(_read(path), path.parent)
