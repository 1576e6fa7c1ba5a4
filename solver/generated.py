"""Modules the solver writes and imports: numba kernels specialised by code generation.

A generated module is written once per distinct text (its digest in the file name) to
the version's folder of the kernel cache (solver/kernel_cache.py), which also keeps its
compiled kernels, else to the temporary folder. It is registered in sys.modules
before it runs: numba's cache records a parallel kernel's module by name and imports
it by that name when it loads the kernel (a module not in sys.modules is recorded as
'<dynamic>', and such cache entries fail to load in a later process).
"""
from __future__ import annotations

import hashlib
import importlib.util
import os
import sys
import tempfile
from pathlib import Path
from types import ModuleType

from solver import kernel_cache


def _folders(kind: str) -> list[Path]:
    """Where a generated module may go: the user's cache, else the system's temporary folder."""
    temporary = Path(tempfile.gettempdir()) / f"mpm-solver-{os.getuid() if hasattr(os, 'getuid') else 'user'}"
    return [kernel_cache.modules_folder(kind), temporary / f"v-{kernel_cache.version_key()}" / kind]


def _name(stem: str, text: str) -> str:
    return f"{stem}_{hashlib.sha256(text.encode()).hexdigest()[:16]}"


def write(kind: str, stem: str, text: str) -> Path:
    """The file of `text` in the `kind` folder, (re)written only when its text changed.
    Written to a temporary file and renamed: processes starting together each see a whole file."""
    for folder in _folders(kind):
        path = folder / f"{_name(stem, text)}.py"
        try:
            if path.is_file() and path.read_text() == text:
                return path
            folder.mkdir(parents=True, exist_ok=True)
            temporary = path.with_name(f".{path.name}.{os.getpid()}.tmp")
            temporary.write_text(text)
            os.replace(temporary, path)
            return path
        except OSError:
            continue
    raise OSError(f"nowhere to write generated kernels: tried {', '.join(map(str, _folders(kind)))}")


def load(kind: str, stem: str, text: str) -> ModuleType:
    """The module `solver._generated.<stem>_<digest>` of `text`, written (see `write`) and imported
    once: two texts of one stem (a material's lines with other constants) are two modules."""
    name = f"solver._generated.{_name(stem, text)}"
    if name in sys.modules:
        return sys.modules[name]
    spec = importlib.util.spec_from_file_location(name, write(kind, stem, text))
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module
