"""Absorbing (Lysmer-Kuhlemeyer) boundaries let a wave leave the grid.

A linear elastic bar between two absorbing faces (x- and x+) starts with a Gaussian
velocity pulse in its middle, which splits into two waves running to the faces. Once
both have reached the faces and travelled a pulse width past them, the energy left in
the bar is the reflected share. Lysmer's dashpots match the impedance of a plane wave
at normal incidence exactly in the continuum; on the grid the pulse (width 5 cells,
Gaussian sigma = 0.05) is resolved well enough that what reflects is well below 1 %
(0.08 % measured in 1D). The same bar with free ends keeps all of its energy, which
checks that the test can fail. In 2D the P wave runs with v_y = 0 imposed everywhere
and the S wave with v_x = 0 (plane waves: the free faces y = const are then traction
free for them), each against its own dashpot, rho c_p or rho c_s.
"""
import math

import pytest

from solver.scene import SceneError
from solver.scene_checks import load_scene
from solver.stepper import ExplicitMPM

E, RHO, NU = 1e6, 1000.0, 0.25
LAM, MU = E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU))
C_P, C_S = math.sqrt((LAM + 2 * MU) / RHO), math.sqrt(MU / RHO)
PULSE = "0.01*exp(-((x-0.5)/0.05)**2)"


def bar(faces, dim=1, wave="p"):
    if dim == 1:
        scene = {"dimension": 1, "grid": {"lower": [0], "upper": [1], "cell_size": 0.01},
                 "bodies": [{"name": "bar", "material": "m", "geometry": {"type": "box", "lower": [0], "upper": [1]},
                             "initial_velocity": [PULSE]}], "boundary_conditions": []}
    else:
        held = [None, 0.0] if wave == "p" else [0.0, None]       # the component that stays zero
        moving = [PULSE, 0.0] if wave == "p" else [0.0, PULSE]
        scene = {"dimension": 2, "grid": {"lower": [0, 0], "upper": [1, 0.1], "cell_size": 0.01},
                 "bodies": [{"name": "bar", "material": "m", "initial_velocity": moving,
                             "geometry": {"type": "box", "lower": [0, 0], "upper": [1, 0.1]}}],
                 "boundary_conditions": [{"type": "velocity", "velocity": held,
                                          "where": {"type": "box", "lower": [0, 0], "upper": [1, 0.1]}}]}
    scene["materials"] = {"m": {"model": "linear_elastic", "density": RHO, "youngs_modulus": E, "poisson_ratio": NU}}
    scene["boundary_conditions"] += [{"type": "absorbing", "face": face} for face in faces]
    scene["time"] = {"end": 1.0}
    return scene


def energy_left(scene, speed):
    """(kinetic + strain energy) / the initial kinetic energy, after the waves (from x = 0.5)
    have run 0.8: to the faces and a pulse width and a half past them."""
    sim = ExplicitMPM(load_scene(scene))
    start = sim.energies().kinetic
    while sim.time < 0.8 / speed:
        sim.advance(sim.stable_time_step(0.5))
    energies = sim.energies()
    return (energies.kinetic + energies.strain) / start, energies.boundary_work / start


def test_a_p_wave_leaves_a_1d_bar():
    left, work = energy_left(bar(("x-", "x+")), C_P)
    assert left < 0.01
    assert left - work == pytest.approx(1.0, rel=0.01)     # what left is the dashpots' work
    assert energy_left(bar(()), C_P)[0] == pytest.approx(1.0, rel=0.01)   # free ends reflect it all


@pytest.mark.parametrize("wave,speed", [("p", C_P), ("s", C_S)])
def test_plane_waves_leave_a_2d_strip(wave, speed):
    assert energy_left(bar(("x-", "x+"), 2, wave), speed)[0] < 0.01


def test_absorbing_face_needs_one_elastic_material():
    scene = bar(("x+",))
    scene["materials"]["m"] = {"model": "fluid", "density": RHO, "bulk_modulus": 1e6}
    with pytest.raises(SceneError, match=r"boundary_conditions\[0\]\.face: the bodies that reach this face"):
        load_scene(scene)
    scene = bar(("x+", "x+"))
    with pytest.raises(SceneError, match=r"boundary_conditions\[1\]\.face: face 'x\+' already has a boundary"):
        load_scene(scene)
