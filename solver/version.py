"""The solver's version, written into each result file (solver/results.py).

Here rather than in solver/__init__.py, which imports the runner when `solver.run` is
read: the runner takes the version from this module, not from its own package.
"""
__version__ = "0.1.0"
