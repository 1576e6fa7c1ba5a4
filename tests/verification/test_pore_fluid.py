"""Saturated soil (two-phase u-p MPM, solver/pore_fluid.py) against Terzaghi's consolidation
and the undrained response (the cases are in pore_fluid_cases.py; errors and times in
docs/benchmarks.md, "Saturated soil", from benchmarks/two_phase.py)."""
from __future__ import annotations

import numpy as np
import pytest

import pore_fluid_cases as pc


class TestTerzaghi:
    """The column drained at its top, from the undrained state p = q. The degree of
    consolidation U is the mean of p; its exact values are 0.5 at Tv = 0.197 and 0.9 at
    Tv = 0.848. The tolerance 0.01 is the discretisation's share: on 10 cells the measured
    error is 0.0013 and 0.0024, on 20 cells 0.004 (the dynamic start of the drainage:
    consolidation here takes ~230 wave transits, not infinitely many), so 0.01 leaves
    room for neither a wrong c_v (c_v 5 % off moves U(0.197) by 0.013) nor a wrong drainage."""

    def test_the_degree_of_consolidation_follows_terzaghi(self):
        measured = pc.consolidation(10)
        for tv, exact in ((0.197, 0.5), (0.848, 0.9)):
            assert abs(measured[tv][0] - exact) < 0.01, f"Tv = {tv}: U = {measured[tv][0]:.4f}, exact {exact}"
        # the isochrone at Tv = 0.848, particle by particle: 1.25 % of q measured on 10 cells
        assert measured[0.848][1] < 0.03

    @pytest.mark.slow
    def test_the_isochrones_converge_at_first_order_in_h(self):
        """max |p - p_exact| / q over the particles at Tv = 0.05 and 0.197, on 10, 20 and 40 cells:
        the particle values carry the cell-constant skeleton's volume change (an O(h) error
        near the steep front), so first order is what the scheme can give; measured 0.93-1.0.
        U on 40 cells: within 0.015 of the exact (measured 0.010 at Tv = 0.05, 0.005 at 0.197: the
        drainage's dynamic start, which refinement does not remove)."""
        errors = [pc.consolidation(cells, tvs=(0.05, 0.197)) for cells in (10, 20, 40)]
        for tv in (0.05, 0.197):
            for coarse, fine in zip(errors, errors[1:]):
                order = pc.isochrone_order(coarse[tv][1], fine[tv][1])
                assert order > 0.8, f"Tv = {tv}: observed order {order:.2f}"
            assert abs(errors[-1][tv][0] - pc.terzaghi_degree(tv)) < 0.015

    @pytest.mark.slow
    @pytest.mark.parametrize("model", ["mohr_coulomb", "linear_elastic"])
    def test_every_soil_model_consolidates_alike(self, model):
        measured = pc.consolidation(10, model=model)
        assert abs(measured[0.197][0] - 0.5) < 0.01

    @pytest.mark.slow
    def test_a_3d_column_consolidates_as_in_2d(self):
        measured = pc.consolidation(10, dim=3)
        assert abs(measured[0.197][0] - 0.5) < 0.01
        assert abs(measured[0.848][0] - 0.9) < 0.01


class TestAxisymmetric:
    """A cylinder of radius 3 h about the axis (slip at r = 3 h, the axis free to move but for
    v_r = 0 there), unloaded, from p = 0, its top held at p = q: the water enters as in Terzaghi's
    column (p = q - Terzaghi's, sigma' = p, the total stress 0), with no radial motion. The
    pore pressure's hoop force V_p p_p N_I / r_p balances its radial gradient's; without it the
    rings move out (v_r 0.07 m/s) and the isochrone is 6 q off at Tv = 0.848. Asserted: the
    plane column's U and isochrone error to 1e-9 (round-off: measured 2e-15; the rings' volumes
    change every sum's terms), and Terzaghi's U to the plane case's 0.01 (measured +0.0030 at
    Tv = 0.197, +0.0025 at 0.848)."""

    def test_an_axisymmetric_column_swells_as_the_plane_one(self):
        plane = pc.consolidation(10, tvs=(0.197, 0.848), swelling=True, across=3)
        ring = pc.consolidation(10, tvs=(0.197, 0.848), swelling=True, across=3, axisymmetric=True)
        for tv in (0.197, 0.848):
            assert abs(ring[tv][0] - pc.terzaghi_degree(tv)) < 0.01, f"Tv = {tv}: U = {ring[tv][0]:.4f}"
            assert ring[tv][0] == pytest.approx(plane[tv][0], abs=1e-9)
            assert ring[tv][1] == pytest.approx(plane[tv][1], abs=1e-9)


class TestSeepage:
    """The unloaded column from p = 0, drained at its top, comes to rest hydrostatic,
    p = rho_w g_n (H - z), where Darcy's flux vanishes. Asserted: within rho_w g h of it (the
    drained face's known first-order error, h / H = 0.1 of rho_w g H on 10 cells; measured 0.054),
    and gravity given as the scene's `body_force` gives the same pressures (Darcy's law takes the
    step's body acceleration; with gravity alone in it, the body-force column stays near p = 0:
    0.97 of rho_w g H off)."""

    def test_the_water_comes_to_rest_hydrostatic_under_gravity_or_an_equal_body_force(self):
        under_gravity = pc.seepage_to_hydrostatic()
        under_body_force = pc.seepage_to_hydrostatic(gravity_as_body_force=True)
        assert np.abs(under_gravity).max() < 0.1
        assert np.abs(under_body_force - under_gravity).max() < 1e-9


class TestUndrained:
    """A sealed column loaded at once and damped to rest: the pore water takes the share
    (K_w/n) / (K_w/n + E_oed) of the load, B ~ 1 for water. Asserted to 1e-4 (water: the
    exact share is 0.99977, a share of 1 - or a skeleton carrying it all - fails) and to
    0.005 for a fluid three times the skeleton's stiffness (share 0.75; measured 0.7473)."""

    def test_water_carries_the_load(self):
        share, mean, exact = pc.undrained(pc.WATER, end=0.02)
        assert share == pytest.approx(exact, abs=1e-4)
        assert mean == pytest.approx(exact, abs=1e-3)

    def test_a_saturated_cam_clay_passes_the_load_to_the_water(self):
        """Modified Cam-Clay with a pore fluid: the clay, stress-free at the start, has the
        stiffness of its minimum_pressure (1 % of p_c: K = (1 + e0) p_min / kappa) and the
        water, 10^4 times stiffer, takes all but 3e-5 of the load; a 1e-4 tolerance as for
        the elastic skeleton fails a skeleton carrying more than 1e-4 of it."""
        from test_cam_clay import CLAY, E0, KAPPA, NU, PC0
        bulk = (1 + E0) * 0.01 * PC0 / KAPPA
        shear = 3 * bulk * (1 - 2 * NU) / (2 * (1 + NU))
        share, mean, exact = pc.undrained(pc.WATER, end=0.02, skeleton=CLAY,
                                          oedometric_modulus=bulk + 4 * shear / 3)
        assert share == pytest.approx(exact, abs=1e-4)
        assert mean == pytest.approx(exact, abs=1e-3)

    def test_a_compressible_fluid_shares_the_load_with_the_skeleton(self):
        share, mean, exact = pc.undrained({**pc.FLUID, "hydraulic_conductivity": 1.0e-8}, end=0.5)
        assert share == pytest.approx(exact, abs=5e-3)
        assert mean == pytest.approx(exact, abs=5e-3)


class TestFastWave:
    """A step load on the sealed, undrained column: the compression front carries the water
    with the skeleton at c = sqrt((K' + 4G/3 + K_w/n) / rho) = 44.7 m/s (rho the mixture's
    density), twice the dry skeleton's 22.4 m/s. The speed between two depths (0.3 and 0.7 m) from
    the arrival of half the undrained pore pressure; the tolerance is the front's own spreading
    between the probes (its 1/4-to-3/4 rise time grows by 7.4 % of the transit on 20 cells), within
    which the grid's dispersion may move its midpoint; measured 3.0 % slow. A speed without the
    fluid's K_w/n (22.4), or with K_w in place of K_w/n (35.4), fails."""

    def test_the_front_travels_at_the_undrained_speed(self):
        speed, exact, spreading = pc.fast_wave(20)
        assert abs(speed - exact) / exact < spreading, f"{speed:.2f} m/s against {exact:.2f}"

    @pytest.mark.slow
    def test_the_front_speed_converges_with_the_grid(self):
        """10, 20, 40, 80 cells: 3.6, 3.0, 1.9, 1.2 % slow (~h^(2/3), the dispersive spreading of a step)."""
        errors = []
        for cells in (10, 20, 40, 80):
            speed, exact, spreading = pc.fast_wave(cells)
            assert abs(speed - exact) / exact < spreading
            errors.append(abs(speed - exact) / exact)
        assert all(fine < coarse for coarse, fine in zip(errors, errors[1:])), errors
