"""The step architecture: each scheme calls the phases and the hook points in the
order of its algorithm, for every backend and formulation, and physics added as a
hook acts on the step."""
from __future__ import annotations

import copy

import numpy as np
import pytest

from solver import step
from solver.scene_checks import load_scene
from solver.stepper import ExplicitMPM

SCENE = {
    "name": "hooks", "dimension": 2,
    "method": {"scheme": "musl", "shape_function": "quadratic_bspline", "transfer": "flip"},
    "grid": {"lower": [0.0, 0.0], "upper": [1.0, 1.0], "cell_size": 0.1},
    "materials": {"m": {"model": "linear_elastic", "density": 1000, "youngs_modulus": 1e5, "poisson_ratio": 0.3}},
    "bodies": [{"name": "block", "material": "m", "initial_velocity": [0.5, 0.0],
                "geometry": {"type": "box", "lower": [0.3, 0.3], "upper": [0.6, 0.6]}}],
    "boundary_conditions": [{"type": "wall", "face": "y-", "mode": "slip"}],
    "time": {"end": 1.0, "dt": 1e-3},
}

# The hook points each scheme passes, in order (constrain: which grid velocity, recorded or not).
ORDER = {
    "usl": ["begin_step", "after_forces", "before_update", "constrain v_old", "constrain v_new recorded", "after_g2p",
            "after_kinematics v_new", "after_stress", "end_step"],
    "musl": ["begin_step", "after_forces", "before_update", "constrain v_old", "constrain v_new recorded", "after_g2p",
             "constrain v_new", "after_kinematics v_new", "after_stress", "end_step"],
    "usf": ["begin_step", "constrain v_old", "after_kinematics v_old", "after_stress", "after_forces",
            "before_update", "constrain v_old", "constrain v_new recorded", "after_g2p", "end_step"],
}


class Recorder:
    """A hook at every point, writing down what it was called with."""

    def __init__(self, sim):
        self.sim, self.calls = sim, []

    def _which(self, v):
        return "v_old" if v is self.sim.grid.v_old else "v_new" if v is self.sim.grid.v_new else "?"

    def begin_step(self, sim, t_end):
        self.calls.append("begin_step")

    def after_forces(self, sim):
        self.calls.append("after_forces")

    def before_update(self, sim, dt):
        self.calls.append("before_update")

    def constrain(self, grid_mass, v, record):
        self.calls.append(f"constrain {self._which(v)}" + (" recorded" if record else ""))
        return 0.0

    def after_g2p(self, sim, dt):
        self.calls.append("after_g2p")

    def after_kinematics(self, sim, dt, v_grid):
        self.calls.append(f"after_kinematics {self._which(v_grid)}")

    def after_stress(self, sim, dt):
        self.calls.append("after_stress")

    def end_step(self, sim, dt):
        self.calls.append("end_step")


def scene(**method) -> dict:
    out = copy.deepcopy(SCENE)
    out["method"].update(method)
    return out


@pytest.mark.parametrize("formulation,general", [("ulmpm", False), ("ulmpm", True), ("tlmpm", True)])
@pytest.mark.parametrize("scheme", ["usl", "musl", "usf"])
def test_each_scheme_passes_the_hook_points_in_its_order(scheme, formulation, general):
    sim = ExplicitMPM(load_scene(scene(scheme=scheme, formulation=formulation)), general=general)
    assert sim.phases.name == ("general" if general or scheme == "usf" or formulation == "tlmpm" else "fused")
    recorder = Recorder(sim)
    sim.add_hook(recorder)
    sim.advance(1e-3)
    assert recorder.calls == ORDER[scheme]


def test_the_backend_is_the_first_that_supports_the_scene():
    assert step.backend_for(load_scene(scene())) is step.FusedPhases
    assert step.backend_for(load_scene(scene(shape_function="gimp"))) is step.GeneralPhases
    assert step.backend_for(load_scene(scene()), general=True) is step.GeneralPhases


class NodalGravity:
    """Gravity added on the grid as m_I g: what the P2G body-force term adds, summed."""

    def __init__(self, g):
        self.g = np.asarray(g)

    def after_forces(self, sim):
        sim.grid.force += sim.grid.mass[:, None] * self.g


@pytest.mark.parametrize("general", [False, True])
def test_a_force_hook_acts_like_the_body_force_it_adds(general):
    """sum_p w_Ip m_p g = m_I g: a hook adding m_I g after P2G loads the block on its
    floor as the scene's gravity does, to round-off (the sums are ordered differently)."""
    resting = scene()
    resting["bodies"][0]["initial_velocity"] = None
    resting["bodies"][0]["geometry"] = {"type": "box", "lower": [0.3, 0.1], "upper": [0.6, 0.4]}
    with_gravity = ExplicitMPM(load_scene({**resting, "gravity": [0.0, -9.81]}), general=general)
    with_hook = ExplicitMPM(load_scene(resting), general=general)
    with_hook.add_hook(NodalGravity([0.0, -9.81]))
    for _ in range(50):
        with_gravity.advance(1e-3)
        with_hook.advance(1e-3)
    a, b = with_gravity.particles, with_hook.particles
    assert np.max(np.abs(a.stress[:, 1, 1])) > 0.1 * 1000 * 9.81 * 0.3   # the floor carries the block's weight
    for name in ("x", "v", "stress"):
        assert np.max(np.abs(getattr(a, name) - getattr(b, name))) <= 1e-12 * np.max(np.abs(getattr(a, name)))


def test_an_added_hook_stays_when_the_grid_is_placed_again():
    """Processes re-place the grid when slabs move, a restart places everything again."""
    sim = ExplicitMPM(load_scene(scene()))
    recorder = Recorder(sim)
    sim.add_hook(recorder)
    sim.place()
    sim.advance(1e-3)
    assert recorder.calls == ORDER["musl"]
