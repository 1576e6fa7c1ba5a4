"""Where numba keeps the solver's compiled kernels: one folder per version of the code.

numba's own cache (`cache=True`) keys an entry by the kernel's source file and by the
bytecode of the kernel itself, not of the functions it calls, and keeps it beside the
file (`__pycache__`) or in a folder named by the file's absolute path. Three things
follow, each of which made processes compile again or run stale code:

* a kernel whose callee changed (a generated module calling `solver.fused._axis`)
  loads the old machine code;
* two checkouts of one commit keep two caches, and two numba versions sharing one
  index drop each other's entries (numba empties an index written by another version);
* processes that save at once lose entries: numba numbers data files 1, 2, ... after
  reading the index, so two savers write the same data file, and the later index
  write drops the other's entry;
* processes started together each compile the kernels they share (the service's
  warm-up, test workers, a run and its precompile helper), since none finds the
  other's entry until it is saved.

So `install()` gives numba a locator for the solver's files (and the generated modules)
that keeps every entry in `<MPM_CACHE_DIR>/v-<digest>/`, where the digest covers the
text of every solver source and the compiler stack: a changed callee is a new folder,
checkouts of one version share one, and no version sees another's. Entries are named
by their place in the package, never by the checkout's path. A save holds a lock on
the index, reads it again, writes the data file (named by the entry's key, so savers
never share a file) and only then the index entry. A compilation holds a lock on the
kernel's index too, taken before numba looks in the cache: a process that wants a kernel
another is compiling waits for it and loads it, so each kernel is compiled once however many
processes start together (`_compile_once`). Folders unused for PRUNE_DAYS are removed.
"""
from __future__ import annotations

import contextlib
import fcntl
import hashlib
import os
import platform
import shutil
import sys
import time
from functools import cache
from importlib import metadata
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent
PRUNE_DAYS = 30
_USED = ".last-used"   # touched at most once a day: the folder's age for pruning


def cache_root() -> Path:
    """$MPM_CACHE_DIR, else mpm-solver/ in the user's cache folder ($XDG_CACHE_HOME or ~/.cache)."""
    explicit = os.environ.get("MPM_CACHE_DIR")
    if explicit:
        return Path(explicit)
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "mpm-solver"


@cache
def version_key() -> str:
    """This process's version of the solver (`digest` of the package); fixed for the process."""
    return digest(PACKAGE)


def digest(package: Path) -> str:
    """A digest of every source of `package` (path in it and text) and of the compiler stack
    (read from the installed packages' metadata: the API process never imports numba)."""
    hasher = hashlib.sha256()
    for name in (*(metadata.version(stack) for stack in ("numba", "llvmlite", "numpy")), sys.version,
                 platform.machine(), sys.platform):
        hasher.update(name.encode() + b"\0")
    for path in sorted(package.rglob("*.py")):
        hasher.update(path.relative_to(package).as_posix().encode() + b"\0" + path.read_bytes() + b"\0")
    return hasher.hexdigest()[:16]


@cache
def version_folder() -> Path:
    """This version's folder; fixed for the process, like the kernels' places in it."""
    return cache_root() / f"v-{version_key()}"


def modules_folder(kind: str) -> Path:
    """Where the generated modules of `kind` are written (solver/generated.py)."""
    return version_folder() / "modules" / kind


def _kernels_folder(py_file: str) -> Path | None:
    """The cache folder of a kernel defined in `py_file`, or None for a file not the solver's."""
    path = Path(py_file).resolve()
    for base, prefix in ((PACKAGE, "solver"), (version_folder().resolve() / "modules", "generated")):
        with contextlib.suppress(ValueError):
            return version_folder() / "kernels" / prefix / path.parent.relative_to(base)
    return None


@cache
def _locator_class():
    from numba.core import caching

    class SolverCacheLocator(caching._SourceFileBackedLocatorMixin, caching._CacheLocator):
        """The solver's kernels, in the version's folder (see the module's docstring)."""

        def __init__(self, py_func, py_file, folder: Path):
            self._py_file = py_file
            self._lineno = py_func.__code__.co_firstlineno
            self._cache_path = str(folder)

        def get_cache_path(self):
            return self._cache_path

        @classmethod
        def from_function(cls, py_func, py_file):
            folder = _kernels_folder(py_file) if os.path.exists(py_file) else None
            if folder is None:
                return None
            self = cls(py_func, py_file, folder)
            try:
                self.ensure_cache_path()
            except OSError:
                return None
            return self

    return SolverCacheLocator


def _index_file_class():
    from numba.core import caching

    class LockedIndexDataCacheFile(caching.IndexDataCacheFile):
        """numba's index and data files, saved so that processes saving at once lose nothing."""

        def save(self, key, data):
            name = f"{self._index_name[:-len('.nbi')]}.{hashlib.sha256(repr(key).encode()).hexdigest()[:16]}.nbc"
            with open(self._index_path + ".lock", "a") as lock:
                fcntl.flock(lock, fcntl.LOCK_EX)
                try:
                    self._save_data(name, data)       # before the index names it: a reader never finds it half
                    overloads = self._load_index()    # again, under the lock: another process may have saved
                    overloads[key] = name
                    self._save_index(overloads)
                finally:
                    fcntl.flock(lock, fcntl.LOCK_UN)

    return LockedIndexDataCacheFile


def is_solver_kernel(dispatcher) -> bool:
    """Whether a numba dispatcher is one of the solver's cached kernels (not one of numba's
    own functions, which it compiles inside a kernel's compilation and never caches)."""
    locator = getattr(getattr(getattr(dispatcher, "_cache", None), "_impl", None), "locator", None)
    return isinstance(locator, _locator_class())


class _CompileLocks:
    """Per kernel index, an exclusive lock on `<index>.compiling` held while a process
    looks for the kernel in the cache and, on a miss, compiles and saves it. Taken under
    numba's compiler lock (one compilation at a time in a process) and reentrant, since a
    kernel compiles its callees inside its own compilation. Processes cannot wait on each
    other in a circle: a process holding a kernel's lock asks only for its callees' locks."""

    def __init__(self) -> None:
        self._held: dict[str, list] = {}     # path -> [open file, depth]

    @contextlib.contextmanager
    def hold(self, path: str):
        held = self._held.get(path)
        if held is None:
            try:
                handle = open(path, "a")
            except OSError:                  # a read-only cache: compile without the lock
                yield
                return
            fcntl.flock(handle, fcntl.LOCK_EX)
            held = self._held[path] = [handle, 0]
        held[1] += 1
        try:
            yield
        finally:
            held[1] -= 1
            if held[1] == 0:
                del self._held[path]
                fcntl.flock(held[0], fcntl.LOCK_UN)
                held[0].close()


def _compile_once(original):
    """numba's Dispatcher.compile, under the kernel's compile lock for the solver's kernels."""
    from numba.core.compiler_lock import global_compiler_lock

    locks = _CompileLocks()

    def compile(self, sig):
        if not is_solver_kernel(self):
            return original(self, sig)
        index = self._cache._cache_file._index_path
        with global_compiler_lock, locks.hold(index[:-len(".nbi")] + ".compiling"):
            return original(self, sig)

    compile.__wrapped__ = original
    return compile


_installed = False


def install() -> None:
    """Put the solver's locator first in numba's list and its locked saves in place; prune old versions.
    Idempotent; called by solver/jit.py before any kernel is defined."""
    global _installed
    if _installed:
        return
    from numba.core import caching, dispatcher

    caching.CacheImpl._locator_classes.insert(0, _locator_class())
    caching.IndexDataCacheFile = _index_file_class()
    dispatcher.Dispatcher.compile = _compile_once(dispatcher.Dispatcher.compile)
    _installed = True
    with contextlib.suppress(OSError):
        _mark_used(version_folder())
        prune(cache_root())


def _mark_used(folder: Path) -> None:
    folder.mkdir(parents=True, exist_ok=True)
    stamp = folder / _USED
    if not stamp.exists() or time.time() - stamp.stat().st_mtime > 86400:
        stamp.touch()


def prune(root: Path, days: float = PRUNE_DAYS) -> list[Path]:
    """Remove the version folders under `root` not used for `days`; the removed folders."""
    removed = []
    for folder in root.glob("v-*"):
        stamp = folder / _USED
        with contextlib.suppress(OSError):
            if folder != version_folder() and time.time() - stamp.stat().st_mtime > days * 86400:
                shutil.rmtree(folder, ignore_errors=True)
                removed.append(folder)
    return removed

