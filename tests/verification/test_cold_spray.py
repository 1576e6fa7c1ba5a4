"""E17, cold spray ([K] 4.3): a copper sphere (R = 10 um) into a copper substrate at 600 m/s.

[K] publishes plots only, and says the axisymmetric and 3D models give "quite similar"
results. What is asserted:
- momentum: the two bodies exchange momentum through the single field or the contact
  correction, both conservative; only the fixed bottom can take momentum away: while the
  impact starts, the bodies lose no more momentum than the bottom's impulse (to round-off);
- energy: the impact ends with the powder at rest and its kinetic energy turned into plastic
  work (read from the adiabatic temperature rise), strain energy and waves; nothing may make
  energy: W_p + KE + SE <= KE0;
- (slow) the full examples: the axisymmetric model and the 3D quarter agree on the splat
  within the resolution of the measures (one cell of each grid).
- the published trends (no published numbers for Cu on Cu at these speeds were found):
  Li et al. 2006 (Appl. Surf. Sci. 253:2852, Cu particles, Lagrangian and ALE FE against
  experiment): the flattening and compression ratios increase with the particle velocity, and
  particles of different diameters deform alike; Dykhuizen et al. 1999 (J. Therm. Spray
  Technol. 8:559, Cu on stainless steel): the crater deepens with the impact velocity, the
  splat diameter is much less sensitive to it, and both scale linearly with the diameter.
  The speed trends on the coarse scene at 400, 600 and 800 m/s; (slow) the size similarity on
  the example at d0 = 20 and 40 um.
The unmarked cases run the axisymmetric example on cells twice as large (1358 particles).
"""
import numpy as np
import pytest

from cold_spray import RADIUS, coarse_axisymmetric, impact, plastic_work, splat_measures, variant
from mpm_cases import run_scene

CONTACTS = ("single_field", "friction")


def run_case(scene, tmp_path_factory, name):
    case = run_scene(scene, tmp_path_factory.mktemp(name))
    assert case.result.status == "complete", case.result.message
    return case


@pytest.fixture(scope="module", params=CONTACTS)
def coarse(request, tmp_path_factory):
    scene = coarse_axisymmetric(request.param)
    return scene, run_case(scene, tmp_path_factory, f"cold_spray_{request.param}")


def test_momentum_leaves_only_through_the_fixed_bottom(coarse):
    _, case = coarse
    s = case.series()
    p0 = s["momentum_powder_y"][0]
    total = s["momentum_powder_y"] + s["momentum_substrate_y"]
    wall_impulse = np.abs(np.cumsum(s["reaction_bc0_y"] * s["dt"]))
    # the start of the impact, while the bottom has taken at most 1e-4 of the momentum
    early = wall_impulse <= 1e-4 * abs(p0)
    last = np.flatnonzero(early)[-1]
    # by then the powder has handed the substrate more than 2 % of its momentum ...
    assert abs(s["momentum_substrate_y"][last]) > 0.02 * abs(p0)
    # ... and the bodies together lost no more than what the bottom took
    assert (np.abs(total - p0)[early] - wall_impulse[early]).max() <= 1e-12 * abs(p0)


def test_the_powder_stops_and_its_energy_is_dissipated(coarse):
    scene, case = coarse
    s = case.series()
    kinetic0 = s["kinetic_energy"][0]
    final = case.frame(-1)
    # Rebound: a restitution coefficient e leaves e^2 of KE0; copper particles that rebound
    # at all near the bonding speed do so with e of about 0.2 or less, and elastic waves carry
    # at most a few % of KE0: the kinetic energy left must be well under 10 %.
    assert s["kinetic_energy"][-1] < 0.1 * kinetic0
    # Most of the kinetic energy turns into plastic work (heat) ...
    dissipated = plastic_work(final, scene)
    assert dissipated > 0.5 * kinetic0
    # ... and no energy is made: what is stored plus what plasticity dissipated <= KE0
    assert dissipated + s["total_energy"][-1] <= kinetic0 * (1.0 + 1e-9)


def test_the_splat_flattens_and_digs_a_crater(coarse):
    scene, case = coarse
    start, end = splat_measures(case.frame(0), scene), splat_measures(case.frame(-1), scene)
    assert start["flattening"] == pytest.approx(1.0) and start["crater"] == pytest.approx(0.0, abs=1e-12)
    # A copper sphere at 600 m/s is above copper's critical velocity: it spreads, shortens and
    # the substrate is cratered (not a rebound with a dent).
    assert end["flattening"] > 1.3 and end["height"] < 0.8 and end["crater"] > 0.2
    # The powder keeps its volume (plastic flow is isochoric; at rest its elastic volume change
    # is under 1 %), and its bounding cylinder, D wide and h high, must hold that volume.
    volume = 4.0 / 3.0 * np.pi * RADIUS**3
    diameter, height = end["flattening"] * 2.0 * RADIUS, end["height"] * 2.0 * RADIUS
    assert np.pi * diameter**2 / 4.0 * height >= 0.99 * volume


@pytest.mark.slow
def test_axisymmetric_and_3d_quarter_agree(tmp_path_factory):
    measures = {}
    for dim in (2, 3):
        scene = variant(dim, frames=2)
        measures[dim] = splat_measures(run_case(scene, tmp_path_factory, f"cold_spray_{dim}d").frame(-1), scene)
    # Each measure is read off particle positions: within a cell of each grid (1 and 1.6 um)
    # over d0 = 20 um.
    allowed = (1.0e-6 + 1.6e-6) / (2.0 * RADIUS)
    for key in ("flattening", "height", "crater"):
        assert abs(measures[3][key] - measures[2][key]) <= allowed, (key, measures)


def test_published_speed_trends(tmp_path_factory):
    """Li et al. 2006 and Dykhuizen et al. 1999 on the coarse scene, single field, 400 / 600 /
    800 m/s (`python benchmarks/cold_spray.py --trends` prints the whole series 400-800 m/s at
    both resolutions and with the contact; docs/benchmarks.md, "Against published trends")."""
    measures = {}
    for speed in (400.0, 600.0, 800.0):
        scene = impact(coarse_axisymmetric(), speed)
        measures[speed] = splat_measures(run_case(scene, tmp_path_factory, f"cold_spray_{speed:.0f}").frame(-1), scene)
    # Resolution: each measure reads the extreme particles, within one cell of the surface it
    # stands for: one cell over d0 = 2 um / 20 um = 0.1. A change is resolved when it is larger.
    cell = 0.1
    low, mid, high = (measures[v] for v in (400.0, 600.0, 800.0))
    assert all(m["ejected"] == 0.0 for m in measures.values()), measures   # the splat is all the powder
    # Each 200 m/s step changes every measure by more than a cell (measured 0.17-0.21):
    # Dykhuizen: the crater deepens with speed;
    assert mid["crater"] - low["crater"] > cell and high["crater"] - mid["crater"] > cell, measures
    # Li: the flattening ratio D / d0 increases ...
    assert mid["flattening"] - low["flattening"] > cell and high["flattening"] - mid["flattening"] > cell, measures
    # ... and so does the compression ratio 1 - h / d0: the splat's height falls.
    assert low["height"] - mid["height"] > cell and mid["height"] - high["height"] > cell, measures
    # Dykhuizen: the splat's diameter is much less sensitive to the speed than the crater. In
    # relative terms (the crater starts from nothing): from 400 to 800 m/s the crater grows by a
    # larger factor than D, even with every measure a cell off to the other side (measured: 2.8
    # against 1.29; the bound compares 1.58 with 1.48). In absolute terms it does not hold with
    # the single field: D / d0 grows by 0.39 as the crater by 0.38 (`cold_spray.py --trends`).
    crater_growth = (high["crater"] - cell) / (low["crater"] + cell)
    diameter_growth = (high["flattening"] + cell) / (low["flattening"] - cell)
    assert crater_growth > diameter_growth, measures


@pytest.mark.slow
def test_particles_of_different_sizes_deform_alike(tmp_path_factory):
    """Li et al. 2006 ("similarity for the deformation of particles of different diameters") and
    Dykhuizen et al. 1999 (splat and crater "scale linearly with the diameter"): the example at
    d0 = 20 um and, every length, the cell and the end time doubled, at d0 = 40 um (the same
    cells, particles and steps)."""
    measures = {}
    for size in (1.0, 2.0):
        scene = impact(variant(2, frames=2), size=size)
        measures[size] = splat_measures(run_case(scene, tmp_path_factory, f"cold_spray_size_{size:g}").frame(-1), scene)
    # Copper without conduction has no length of its own: x -> 2 x, t -> 2 t at the same speed
    # leaves the equations the same but for Johnson-Cook's rate factor 1 + C ln(rate / 1 s^-1).
    # The rates scale as v / d0 (3e7 /s at 20 um: the factor is 1 + 0.025 x 17.2 = 1.43); the
    # larger powder halves them: the factor falls by C ln 2 = 0.0173, 1.2 % of the flow stress
    # (at most 1.7 % at any rate above 1 /s). The splat is set by rho v^2 / sigma_y (with the
    # elastic terms, unchanged): 1.7 % less strength acts as 1.7 % more rho v^2, i.e. 0.87 %
    # more speed, 5.2 m/s at 600 m/s. The steepest measure near 600 m/s in the speed series
    # (`cold_spray.py --trends`) is D / d0 at this resolution, 0.0028 per m/s (500 -> 700 m/s): 0.015.
    # (Johnson-Cook damage's rate term moves the failure strain by D4 ln 2 / 1.24 = 0.8 %.)
    # Plus the measures' resolution, one cell over d0: 1 um / 20 um = 0.05. Measured: 0.007
    # (D / d0), 0.004 (h / d0), 0.004 (crater); 0.018 for D / d0 with 13 output frames (the
    # frames' times set the last step of each interval). Not scaling the end time (the 40 um
    # powder stopped at 60 ns, mid-impact) moves h / d0 by 0.14 and fails.
    allowed = 0.015 + 0.05
    assert measures[2.0]["ejected"] == measures[1.0]["ejected"] == 0.0, measures
    for key in ("flattening", "height", "crater"):
        assert abs(measures[2.0][key] - measures[1.0][key]) <= allowed, (key, measures)
