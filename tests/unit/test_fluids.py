"""The fluid and ideal_gas materials, their scene keys and the initial state of gas bodies."""
import math

import numpy as np
import pytest

from solver.examples import load_example
from solver.scene import SceneError
from solver.scene_checks import load_scene
from solver.state import make_materials, make_particles

K, GAMMA, RHO0 = 2.0e6, 7.0, 1000.0


def water(**keys):
    scene = load_example("still_water_2d")
    scene["materials"]["water"] = {"model": "fluid", "density": RHO0, "bulk_modulus": K, "gamma": GAMMA, **keys}
    return scene


def state_of(scene):
    scene = load_scene(scene)
    particles, slices = make_particles(scene)
    return scene, particles, make_materials(scene, slices, particles)


def deform(particles, J, L=None):
    particles.volume[:] = J * particles.volume0
    particles.L[:] = 0.0 if L is None else L


class TestFluid:
    def test_tait_pressure_from_j_and_plane_strain_trace(self):
        _, p, [(fluid, sl)] = state_of(water(viscosity=0.5))
        J = 0.99
        deform(p, J, np.array([[0.3, 0.2], [0.0, -0.1]]))
        fluid.update_stress(p, sl, 1e-4)
        pressure = K * ((1 / J) ** GAMMA - 1)
        # the deviator of D (with D_zz = 0) is traceless: -tr(sigma)/3 is the EOS pressure
        assert -np.trace(p.stress[0]) / 3 == pytest.approx(pressure, rel=1e-12)
        # 2 mu dev(D): xy = mu (L_xy + L_yx), zz = 2 mu (0 - tr D / 3)
        assert p.stress[0, 0, 1] == pytest.approx(0.5 * 0.2, rel=1e-12)
        assert p.stress[0, 2, 2] == pytest.approx(-2 * 0.5 * 0.2 / 3 - pressure, rel=1e-12)
        # compressed water is stiffer: c^2 = K gamma / rho0 (rho/rho0)^(gamma-1)
        assert fluid.wave_speed == pytest.approx(math.sqrt(K * GAMMA / RHO0 * (1 / J) ** (GAMMA - 1)), rel=1e-12)

    def test_at_rest_no_stress(self):
        _, p, [(fluid, sl)] = state_of(water())
        fluid.update_stress(p, sl, 1e-4)
        assert np.all(p.stress == 0.0)
        assert fluid.strain_energy(p, sl) == 0.0

    @pytest.mark.parametrize("cutoff, expected", [(None, K * (1.1**-GAMMA - 1)), (1000.0, -1000.0), (0.0, 0.0)])
    def test_tension_cut_off(self, cutoff, expected):
        _, p, [(fluid, sl)] = state_of(water(tension_cutoff=cutoff))
        deform(p, 1.1)
        fluid.update_stress(p, sl, 1e-4)
        assert -p.stress[0, 1, 1] == pytest.approx(expected, rel=1e-12, abs=1e-12)

    def test_stored_energy_is_the_work_of_the_pressure(self):
        _, p, [(fluid, sl)] = state_of(water())
        J = np.linspace(1.0, 0.97, 3001)
        # W(J) = -int_1^J p dJ', by the trapezoidal rule on a fine grid
        work = -np.trapezoid(K * (J**-GAMMA - 1), J)
        deform(p, J[-1])
        per_volume = fluid.particle_strain_energy(p, sl)[0] / p.volume0[0]
        assert per_volume == pytest.approx(work, rel=1e-6)

    def test_negative_cut_off_is_an_error_naming_the_field(self):
        with pytest.raises(SceneError) as caught:
            load_scene(water(tension_cutoff=-1.0))
        assert [e["path"] for e in caught.value.errors] == ["materials.water.tension_cutoff"]


def sod():
    return load_example("sod_shock_tube")


class TestIdealGas:
    def test_bodies_give_mass_energy_and_pressure(self):
        scene, p, [(gas, sl)] = state_of(sod())
        left = p.body == 0
        assert np.allclose(p.mass[left], 1.0 * p.volume0[left]) and np.allclose(p.mass[~left], 0.125 * p.volume0[~left])
        e = p.extra["internal_energy"]
        assert np.allclose(e[left], 2.5) and np.allclose(e[~left], 2.0)   # p / ((gamma - 1) rho)
        assert np.allclose(p.stress[left], -1.0 * np.eye(3)) and np.allclose(p.stress[~left], -0.1 * np.eye(3))
        assert gas.wave_speed == pytest.approx(math.sqrt(1.4), rel=1e-12)

    def test_adiabatic_compression_follows_the_isentrope(self):
        """Uniform compression L = -a: p / rho^gamma stays constant (second order in dt)."""
        scene = sod()
        scene["materials"]["air"]["artificial_viscosity"] = {"quadratic": 0.0, "linear": 0.0}
        _, p, [(gas, sl)] = state_of(scene)
        rate, dt, steps = -2.0, 1e-3, 200
        J = 1.0
        p.L[:, 0, 0] = rate
        for _ in range(steps):
            J *= 1 + rate * dt
            p.volume[:] = J * p.volume0
            gas.update_stress(p, sl, dt)
        rho = p.mass / p.volume
        pressure = -p.stress[:, 0, 0]
        entropy = pressure / rho**1.4
        assert J < 0.7
        assert np.allclose(entropy[p.body == 0], 1.0, rtol=1e-4)
        assert np.allclose(entropy[p.body == 1], 0.1 / 0.125**1.4, rtol=1e-4)

    def test_artificial_viscosity_only_in_compression(self):
        scene, p, [(gas, sl)] = state_of(sod())
        h = min(scene.cell_sizes())   # L_e: the smallest cell side
        for rate, expect_q in ((-5.0, True), (5.0, False)):
            p.extra["internal_energy"][:] = 2.5
            p.volume[:] = p.volume0 * (1 + rate * 1e-6)
            p.L[:, 0, 0] = rate
            gas.update_stress(p, sl, 1e-6)
            rho = p.mass[0] / p.volume[0]
            eos = 0.4 * rho * p.extra["internal_energy"][0]
            q = -p.stress[0, 0, 0] - eos
            if expect_q:
                a = math.sqrt(1.4 * 0.4 * 2.5)   # sqrt(gamma p / rho) = sqrt(gamma (gamma - 1) e) before the step
                expected = rho * h * (2.25 * h * rate**2 - 0.06 * a * rate)
                assert q == pytest.approx(expected, rel=1e-4)
            else:
                assert q == pytest.approx(0.0, abs=1e-12)

    def test_the_viscosity_keys_are_checked(self):
        scene = sod()
        scene["materials"]["air"]["artificial_viscosity"] = {"quadratic": -1.0, "linear": 0.06, "cubic": 1}
        with pytest.raises(SceneError) as caught:
            load_scene(scene)
        paths = {e["path"] for e in caught.value.errors}
        assert paths == {"materials.air.artificial_viscosity.quadratic", "materials.air.artificial_viscosity.cubic"}

    def test_a_gas_body_needs_its_initial_pressure(self):
        scene = sod()
        del scene["bodies"][1]["initial_pressure"]
        with pytest.raises(SceneError) as caught:
            load_scene(scene)
        assert [(e["path"], e["message"]) for e in caught.value.errors] == [
            ("bodies[1].initial_pressure", "required for an 'ideal_gas' material")]
