"""The one base class of the errors the solver raises on purpose.

Every such error carries a message written for the person who gave the input
(a scene, an expression, a checkpoint, an example name) or who ran the
simulation (an instability naming the step, particle and quantity), and the
structured fields that say the same to a program (`SceneError.errors`,
`Instability.step`, ...): callers branch on the class and read the fields,
never parse the message. Each subclass also keeps the built-in class it was
before (ValueError, KeyError, RuntimeError), so code that catches those still does.
"""
from __future__ import annotations


class SolverError(Exception):
    """Base of the solver's own errors (see the module docstring)."""
