"""Explicit material point method solver: scene in, HDF5 result out.

    from solver import run
    result = run("examples/two_disks.json", "out/two_disks")

`run` is imported lazily so that the schema (`solver.scene`) can be used
without loading numba.
"""
from solver.version import __version__

__all__ = ["run", "__version__"]


def __getattr__(name):
    if name == "run":
        from solver.runner import run

        return run
    raise AttributeError(f"module 'solver' has no attribute {name!r}")
