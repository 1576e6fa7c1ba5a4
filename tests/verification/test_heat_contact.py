"""Heat with contact "friction" (solver/thermal.py, solver/contact.py): perfect thermal contact
where the bodies touch, and the frictional work as heat (cases in heat_contact_cases.py;
errors and times in docs/benchmarks.md, "Heat", "Contact: conduction and frictional heat")."""
from __future__ import annotations

import numpy as np
import pytest

import heat_contact_cases as hcc

# sum m c T of a run is summed in floating point every step: with T near 0 K (the sliding
# block) or at 300-400 K over 400 steps (the halves), a relative 1e-12 is round-off
ROUND_OFF = 1e-12


def test_two_bodies_in_contact_conduct_as_the_single_field():
    """The bar cut in two bodies conducts exactly as the bar: at the touching node both fields
    take the capacity-weighted temperature, which is the single field's value there."""
    difference, error = hcc.split_bar_against_one(cells=24)
    assert difference <= 1e-12   # of temperatures of order 1
    assert error < 0.1           # E12's particle error at 24 cells (grid error 3.5e-2: docs/benchmarks.md)


def test_heat_crosses_the_contact_and_the_thermal_energy_is_kept():
    found = hcc.insulated_halves()
    assert abs(found["end"] - found["start"]) <= ROUND_OFF * found["start"]
    # the right half (300 K) took heat: over 400 steps of dt = h^2 / 4 (t = 0.16, diffusion length
    # sqrt(t) = 0.4 of the unit bar) a good part of the 50 K x (m c)/2 difference crosses
    capacity_half = found["start"] / 700.0   # sum m c of one half (halves of equal m c, at 400 and 300 K)
    assert found["crossed"] > 0.1 * 50.0 * capacity_half


@pytest.mark.parametrize("support", ["wall", "rigid"])
def test_frictional_work_heats_the_sliding_block(support):
    """Heat = -friction_work to round-off (every contact node of the block holds heat; the rigid
    slab holds none and takes none), and = mu N d: friction is mu m g cos theta while the block
    slides (PIC: the start-up vibration of the block, which with FLIP modulates N by 1 %, is
    damped). The bound is the incline test's: a within 1 % of g (sin - mu cos) is the friction
    force within 0.01 a / (g sin - a) = 0.92 %; measured 9e-5 (wall), 3e-4 (rigid)."""
    found = hcc.sliding_heat(support, transfer="pic")
    assert found["unheld"] == 0.0
    assert found["total_heat"] == pytest.approx(found["total_friction_heat"], rel=ROUND_OFF)
    assert found["heat"] == pytest.approx(found["friction_heat"], rel=ROUND_OFF)
    assert found["heat"] == pytest.approx(found["coulomb"], rel=0.0092)
    # the heat enters at the contact nodes: the block's upper half, reached only by conduction
    # (diffusion length sqrt(k t / (rho c)) = 0.5 mm in 0.3 s, a fortieth of a cell), stays cold
    assert found["bottom_T"] > 0.0
    assert found["upper_T"] < 1e-3 * found["bottom_T"]
