"""A base commit's material kernel modules, loaded beside this tree's for side-by-side timing.

The kernel's text at the commit is written to a folder and imported under another name;
its `from solver.materials.kernels import objective` is pointed at the commit's objective.py
too (a change there, e.g. what numba inlines, belongs to the base it was measured against).
The other solver modules it imports are this tree's.
"""
from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
KERNELS = "solver/materials/kernels"


def _module(name: str, path: Path):
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _text(base: str, path: str) -> str:
    """The file at the commit, compiled afresh (numba's cache of a module loaded from a path does not reload)."""
    return subprocess.run(["git", "show", f"{base}:{path}"], capture_output=True, text=True, check=True,
                          cwd=ROOT).stdout.replace("cache=True", "cache=False")


def load(base: str, kernel: str, folder: Path):
    """The module solver/materials/kernels/<kernel>.py as it is at `base` (folder: where its text goes)."""
    objective_name = f"objective_{base}".replace("~", "_").replace("^", "_")
    objective_path = folder / f"{objective_name}.py"
    if not objective_path.exists():
        objective_path.write_text(_text(base, f"{KERNELS}/objective.py"))
    if objective_name not in sys.modules:
        sys.modules[objective_name] = _module(objective_name, objective_path)
    text = _text(base, f"{KERNELS}/{kernel}.py").replace(
        "from solver.materials.kernels import objective", f"import {objective_name} as objective")
    text = text.replace("from solver.materials.kernels import eos, objective",
                        f"from solver.materials.kernels import eos\nimport {objective_name} as objective")
    path = folder / f"{kernel}_base.py"
    path.write_text(text)
    return _module(f"{kernel}_base", path)
