"""Heat with contact (a field per body, solver/contact.py; the exchange in solver/thermal.py):
cases for tests/verification/test_heat_contact.py and benchmarks/heat_contact.py.

- E12's bar cut in two bodies at x = 1/2 with contact "friction": where the bodies touch
  their fields share one temperature (perfect thermal contact), so the bar conducts as
  the single field conducts it.
- The same two halves at 400 K and 300 K, insulated: the heat crosses the contact and
  sum m c T stays what it was (round-off).
- A block sliding down an incline (test_contact.py's, 30 degrees, mu = 0.3) on a
  frictional wall or on a rigid slab, conducting: the frictional work goes into the
  block's temperature, sum m c T rises by -friction_work, and that is mu N times the
  distance slid, N = m g cos theta.
"""
from __future__ import annotations

import copy
import math

import numpy as np

import heat_cases as hc
from test_contact import G, incline

from solver.scene_checks import load_scene
from solver.stepper import ExplicitMPM

THETA, MU = 30.0, 0.3


def split_bar_scene(cells: int, dt: float, end: float = 0.05, temperatures=None) -> dict:
    """E12 (heat_cases.bar_scene) as two bodies meeting at x = 1/2, with contact "friction".
    With `temperatures` (left, right): those start temperatures and no held faces (insulated)."""
    scene = hc.bar_scene(cells, dt, end)
    body = scene["bodies"][0]
    scene["bodies"] = [{**copy.deepcopy(body), "name": name, "geometry": {"type": "box", "lower": [a], "upper": [b]}}
                       for name, a, b in (("left", 0.0, 0.5), ("right", 0.5, 1.0))]
    scene["contact"] = {"model": "friction", "friction": MU}
    if temperatures is not None:
        for b, T in zip(scene["bodies"], temperatures):
            b["initial_temperature"] = T
        scene["boundary_conditions"] = [c for c in scene["boundary_conditions"] if c["type"] != "temperature"]
    return scene


def particle_temperatures(scene: dict, dt: float) -> tuple[np.ndarray, np.ndarray, ExplicitMPM]:
    """(x_p, T_p) sorted by x at the scene's end, and the simulation."""
    sim = ExplicitMPM(load_scene(scene))
    hc.advance_to(sim, scene["time"]["end"], dt)
    p = sim.particles
    order = np.argsort(p.x[:, 0])
    return p.x[order, 0], p.extra["temperature"][order], sim


def split_bar_against_one(cells: int = 24, dt: float | None = None) -> tuple[float, float]:
    """(max |T_p(two bodies) - T_p(one body)|, max |T_p(two bodies) - exact|) of E12 at t = 0.05."""
    dt = dt or 0.25 / cells**2
    x, one, _ = particle_temperatures(hc.bar_scene(cells, dt), dt)
    x2, two, _ = particle_temperatures(split_bar_scene(cells, dt), dt)
    assert np.array_equal(x, x2)
    return float(np.max(np.abs(two - one))), float(np.max(np.abs(two - hc.bar_exact(x2, 0.05))))


def insulated_halves(cells: int = 24, steps: int = 400) -> dict[str, float]:
    """Two halves at 400 K and 300 K, touching, insulated: sum m c T at the start and the end,
    and the heat the right half took."""
    dt = 0.25 / cells**2
    sim = ExplicitMPM(load_scene(split_bar_scene(cells, dt, steps * dt, temperatures=(400.0, 300.0))))
    p = sim.particles
    right = p.body == 1

    def right_heat():
        return float(np.sum(p.mass[right] * p.extra["heat_capacity"][right] * p.extra["temperature"][right]))

    start, right_start = sim.thermal_series()["thermal_energy"], right_heat()
    for _ in range(steps):
        sim.advance(dt)
    return {"start": start, "end": sim.thermal_series()["thermal_energy"], "crossed": right_heat() - right_start}


def sliding_scene(support: str, end: float = 0.3, **method) -> dict:
    """test_contact.incline's block (mu = 0.3, 30 degrees) conducting, from 0 K: the heat it
    gains is then not lost in the round-off of sum m c T at room temperature."""
    scene = incline(THETA, MU, support, end=end, **method)
    scene["materials"]["rubber"].update(thermal_conductivity=1.0, specific_heat=1000.0)
    scene["bodies"][0]["initial_temperature"] = 0.0
    return scene


def sliding_heat(support: str, end: float = 0.3, start: float = 0.1, **method) -> dict[str, float]:
    """The block's frictional heat between t = start and end, against -friction_work and
    against mu N d (N = m g cos theta, d its centre of mass's slide); the energy balance."""
    scene = sliding_scene(support, end, **method)
    sim = ExplicitMPM(load_scene(scene))
    p = sim.particles
    block = p.body == 0
    mass = float(p.mass[block].sum())

    def state():
        centre = float(np.sum(p.mass[block] * p.x[block, 0]) / mass)
        return centre, sim.thermal_series()["thermal_energy"], -sim.work["friction_work"]

    dt = sim.stable_time_step(0.5)
    initial = sim.energies().balance
    while sim.time < start - 1e-12:
        sim.advance(min(dt, start - sim.time))
    x0, heat0, work0 = state()
    while sim.time < end - 1e-12:
        sim.advance(min(dt, end - sim.time))
    x1, heat1, work1 = state()
    y = p.x[block, 1]
    bottom = y < np.min(y) + 1e-9   # the row of particles on the slope
    upper = y > 0.5 * (np.min(y) + np.max(y))
    T = p.extra["temperature"][block]
    return {"heat": heat1 - heat0, "friction_heat": work1 - work0, "total_heat": heat1,
            "total_friction_heat": work1, "coulomb": MU * mass * G * math.cos(math.radians(THETA)) * (x1 - x0),
            "mechanical_error": sim.energies().balance - initial, "bottom_T": float(T[bottom].mean()),
            "upper_T": float(np.abs(T[upper]).max()), "unheld": sim.conduction.unheld_friction_heat}
