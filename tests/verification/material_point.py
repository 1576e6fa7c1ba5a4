"""A single material point driven by a prescribed velocity gradient, without a grid:
F <- (I + L dt) F, V = det(F) V0, then the model's update_stress, as the stepper does.
`mixed_step` holds chosen normal stresses by iterating on their (shared) strain rate."""
from types import SimpleNamespace

import numpy as np

from solver import materials
from solver.state import Particles


class MaterialPoint:
    """One particle of unit reference volume and the material model acting on it."""

    def __init__(self, config: dict, dim: int = 3, stress=None, temperature=None, rigid_volume=False):
        self.config = materials.REGISTRY[config["model"]].schema.model_validate(config)
        eye = np.eye(dim)[None]
        self.p = Particles(x=np.zeros((1, dim)), v=np.zeros((1, dim)), F=eye.copy(), L=np.zeros((1, dim, dim)),
                           stress=np.zeros((1, 3, 3)), mass=np.array([self.config.density]),
                           volume=np.ones(1), volume0=np.ones(1), id=np.zeros(1, np.int64),
                           body=np.zeros(1, np.int32))
        self.model = materials.create(self.config, dim)
        scene = SimpleNamespace(bodies=[SimpleNamespace(initial_temperature=temperature)])
        materials.init_particles([(self.model, slice(0, 1))], self.p, scene)
        if stress is not None:
            self.p.stress[0] = stress
        self.rigid_volume = rigid_volume   # a rigid motion keeps the volume exactly

    def step(self, L, dt):
        p = self.p
        p.L[0] = L
        p.F[0] = (np.eye(len(L)) + dt * np.asarray(L)) @ p.F[0]
        if not self.rigid_volume:
            p.volume[0] = np.linalg.det(p.F[0]) * p.volume0[0]
        self.model.update_stress(p, slice(0, 1), dt)

    def mixed_step(self, L, dt, held, target, stiffness, iterations=40):
        """A step with one diagonal rate, shared by the axes `held`, chosen so that
        sigma[a, a] = target there (secant iterations from the previous step's rate,
        the first with the elastic stiffness `stiffness`)."""
        L = np.array(L, dtype=float)
        saved = self.snapshot()
        rate, previous = getattr(self, "_held_rate", 0.0), None
        for _ in range(iterations):
            self.restore(saved)
            for a in held:
                L[a, a] = rate
            self.step(L, dt)
            error = float(np.mean([self.stress[a, a] - target for a in held]))
            if abs(error) <= 1e-13 * max(abs(target), 1.0):
                self._held_rate = rate
                return
            slope = stiffness * dt if previous is None or previous[0] == rate else \
                (error - previous[1]) / (rate - previous[0])
            previous = (rate, error)
            rate -= error / slope
        raise AssertionError("the mixed step did not converge")

    @property
    def stress(self):
        return self.p.stress[0]

    def state(self, name):
        return float(self.p.extra[name][0])

    def snapshot(self):
        return self.p.stress.copy(), {k: a.copy() for k, a in self.p.extra.items()}, self.p.F.copy(), self.p.volume.copy()

    def restore(self, snap):
        stress, extra, F, volume = snap
        self.p.stress[:] = stress
        for k, a in extra.items():
            self.p.extra[k][:] = a
        self.p.F[:] = F
        self.p.volume[:] = volume
