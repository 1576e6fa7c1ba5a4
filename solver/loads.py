"""Body accelerations: gravity plus the scene's body force expressions.

`body_force` is a force per unit mass (an acceleration), in the current (x, y, z)
and reference (X, Y, Z) coordinates and time t, as manufactured solutions need.
"""
from __future__ import annotations

import numpy as np

from solver.expressions import compile_expression

CURRENT = ("x", "y", "z")
REFERENCE = ("X", "Y", "Z")


class BodyLoads:
    def __init__(self, scene):
        dim = scene.dimension
        self.dimension = dim
        self.gravity = np.zeros(dim)
        if scene.gravity is not None:
            self.gravity[:] = scene.gravity
        variables = CURRENT[:dim] + REFERENCE[:dim] + ("t",)
        self.expressions = []
        if scene.body_force is not None:
            self.expressions = [
                compile_expression(c, variables) if isinstance(c, str) else float(c or 0.0)
                for c in scene.body_force
            ]
        self.needs_reference = any(
            not isinstance(e, float) and any(v in REFERENCE for v in e.variables_used) for e in self.expressions
        )
        self._shared = self.gravity.reshape(1, dim).copy()

    @property
    def varies_by_particle(self) -> bool:
        return bool(self.expressions)

    @property
    def any(self) -> bool:
        return self.varies_by_particle or bool(np.any(self.gravity != 0.0))

    def acceleration(self, particles, t: float) -> np.ndarray:
        """(n, dim) per particle, or (1, dim) when it is the same for all."""
        if not self.expressions:
            return self._shared
        dim = self.dimension
        env = {CURRENT[a]: particles.x[:, a] for a in range(dim)}
        if particles.X is not None:
            env.update({REFERENCE[a]: particles.X[:, a] for a in range(dim)})
        env["t"] = t
        acc = np.empty((particles.count, dim))
        for a, e in enumerate(self.expressions):
            acc[:, a] = self.gravity[a] + (e if isinstance(e, float) else e.evaluate(**env))
        return acc
