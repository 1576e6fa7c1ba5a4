"""Heat (solver/thermal.py): validation of the thermal keys and conditions, nothing
thermal in a scene without them, the time step's conduction limit, threads, the
run's fields and series, and the heat of plastic work in the conducted field."""
from __future__ import annotations

import math

import numpy as np
import pytest

from solver import run
from solver.results import read_frame, read_series
from solver.scene_checks import load_scene
from solver.stepper import ExplicitMPM
from solver.summary import summarize
from tests.scene_errors import errors_of

BAR = {"model": "linear_elastic", "density": 2.0, "youngs_modulus": 1.0, "poisson_ratio": 0.0,
       "thermal_conductivity": 4.0, "specific_heat": 3.0}


def scene(dim=1, material=None, conditions=(), dt=None, **top):
    lower, upper = [0.0] * dim, [1.0] * dim
    out = {"dimension": dim, "grid": {"lower": lower, "upper": upper, "cell_size": 0.1},
           "materials": {"bar": dict(material or BAR)},
           "bodies": [{"name": "bar", "material": "bar", "geometry": {"type": "box", "lower": lower, "upper": upper},
                       "initial_temperature": 10.0}],
           "boundary_conditions": list(conditions), "time": {"end": 0.01, "dt": dt}}
    out.update(top)
    return out



class TestValidation:
    def test_a_fixed_dt_above_the_conduction_limit_is_refused_naming_time_dt(self):
        # rho c h^2 / (2 d k) = 2 * 3 * 0.01 / (2 * 1 * 4) = 0.0075
        assert load_scene(scene(dt=0.0075)).time.dt == 0.0075
        [error] = errors_of(scene(dt=0.008))
        assert error["path"] == "time.dt"
        assert "conduction limit" in error["message"] and "0.0075" in error["message"] and "'bar'" in error["message"]

    def test_the_limit_counts_every_axis(self):
        # 2D: rho c / (2 k (1/h^2 + 1/h^2)) = 6 * 0.01 / 16 = 0.00375
        assert errors_of(scene(dim=2, dt=0.004))[0]["path"] == "time.dt"
        load_scene(scene(dim=2, dt=0.00375))

    def test_conduction_needs_a_specific_heat(self):
        material = {k: v for k, v in BAR.items() if k != "specific_heat"}
        assert errors_of(scene(material=material)) == [
            {"path": "materials.bar.specific_heat", "message": "required with thermal_conductivity > 0"}]

    def test_rigid_bodies_take_no_thermal_keys(self):
        data = scene(material={"model": "rigid", "density": 1.0, "thermal_conductivity": 1.0})
        paths = [e["path"] for e in errors_of(data)]
        assert "materials.bar.thermal_conductivity" in paths

    def test_conduction_runs_with_tlmpm(self):   # (tests/verification/test_heat.py, TestE12BarTLMPM)
        assert load_scene(scene(method={"formulation": "tlmpm"})).method.formulation == "tlmpm"

    def test_expansion_is_for_the_solid_models(self):
        fluid = {"model": "fluid", "density": 1.0, "bulk_modulus": 1.0, "thermal_expansion": 1e-3}
        [error] = errors_of(scene(material=fluid))
        assert error["path"] == "materials.bar.thermal_expansion"

    def test_a_thermal_condition_needs_a_conducting_material(self):
        material = {k: v for k, v in BAR.items() if k not in ("thermal_conductivity", "specific_heat")}
        [error] = errors_of(scene(material=material, conditions=[{"type": "heat_flux", "face": "x+", "flux": 1.0}]))
        assert error["path"] == "boundary_conditions[0].type"

    def test_a_temperature_condition_takes_a_face_or_a_box(self):
        both = {"type": "temperature", "face": "x-", "temperature": 1.0,
                "where": {"type": "box", "lower": [0.0], "upper": [0.1]}}
        assert errors_of(scene(conditions=[both]))[0]["path"] == "boundary_conditions[0]"
        neither = {"type": "temperature", "temperature": 1.0}
        assert errors_of(scene(conditions=[neither]))[0]["path"] == "boundary_conditions[0]"

    def test_faces_belong_to_the_scene_s_axes(self):
        data = scene(conditions=[{"type": "convection", "face": "y+", "coefficient": 1.0, "ambient": 0.0}])
        [error] = errors_of(data)
        assert error["path"] == "boundary_conditions[0].face"

    def test_temperatures_may_be_expressions_in_t(self):
        data = scene(conditions=[{"type": "temperature", "face": "x-", "temperature": "300 + 2 * t"},
                                 {"type": "heat_flux", "face": "x+", "flux": "sin(t)"}])
        load_scene(data)
        data["boundary_conditions"][0]["temperature"] = "300 + x"
        assert errors_of(data)[0]["path"].startswith("boundary_conditions[0].temperature")


class TestNothingThermalWithoutTheKeys:
    """A scene without thermal keys allocates no thermal state, makes no thermal hook and
    keeps the fused step (tests/regression keeps every example bit for bit)."""

    @pytest.mark.parametrize("material", [
        {"model": "linear_elastic", "density": 1.0, "youngs_modulus": 1.0, "poisson_ratio": 0.3},
        {"model": "linear_elastic", "density": 1.0, "youngs_modulus": 1.0, "poisson_ratio": 0.3,
         "thermal_conductivity": 0.0, "thermal_expansion": 0.0, "specific_heat": 5.0},
    ])
    def test_no_thermal_state_hooks_or_series(self, material):
        sim = ExplicitMPM(load_scene(scene(dim=2, material=material)))
        assert sim.conduction is None
        assert not {"temperature", "heat_flux", "heat_capacity", "conductivity",
                    "expansion_temperature"} & set(sim.particles.extra)
        assert not any(type(h).__module__ == "solver.thermal" for h in sim.hooks._hooks)
        assert sim.phases.name == "fused"
        assert sim.thermal_series() == {}


class TestStep:
    def test_the_adaptive_step_keeps_below_the_conduction_limit(self):
        sim = ExplicitMPM(load_scene(scene(dim=2)))
        limit = 2.0 * 3.0 / (2 * 4.0 * (2 / 0.1**2))
        assert sim.stable_time_step(0.5) == pytest.approx(0.5 * limit, rel=1e-14)

    def test_the_summary_estimates_the_steps_with_the_conduction_limit(self):
        data = load_scene(scene(dim=2))
        limit = 2.0 * 3.0 / (2 * 4.0 * (2 / 0.1**2))
        summary = summarize(data)
        assert summary.dt == pytest.approx(0.5 * limit, rel=1e-14)
        assert summary.estimated_steps == math.ceil(0.01 / (0.5 * limit))

    def test_two_threads_give_one_thread_s_temperatures(self):
        """Only the order of the per-thread nodal sums differs: round-off."""
        results = []
        for threads in (1, 2):
            data = scene(dim=2, conditions=[{"type": "temperature", "face": "x-", "temperature": 50.0},
                                            {"type": "heat_flux", "face": "y+", "flux": 3.0}],
                         parallel={"threads": threads})
            data["grid"]["cell_size"] = 0.02   # 10^4 particles: two blocks of particles
            sim = ExplicitMPM(load_scene(data))
            for _ in range(50):
                sim.advance(2e-4)
            results.append(sim.particles.extra["temperature"].copy())
        assert np.abs(results[0] - results[1]).max() <= 1e-12 * np.abs(results[0]).max()
        assert results[0].max() > 10.0 + 1.0   # heat did come in

    def test_a_run_writes_temperature_heat_flux_and_the_thermal_series(self, tmp_path):
        data = scene(conditions=[{"type": "heat_flux", "face": "x+", "flux": 2.0}],
                     output={"frames": 2, "fields": ["temperature", "heat_flux"], "energies": 1})
        result = run(data, tmp_path)
        assert result.status == "complete"
        frame = read_frame(tmp_path / "result.h5", -1)["fields"]
        assert frame["temperature"].shape == (20,) and frame["heat_flux"].shape == (20, 1)
        assert frame["heat_flux"].min() < 0.0   # heat flows towards -x, away from the heated face
        series = read_series(tmp_path / "result.h5")
        gain = series["thermal_energy"] - series["thermal_energy"][0]
        assert np.allclose(gain, series["boundary_heat"], rtol=1e-12, atol=1e-12)
        assert series["boundary_heat"][-1] == pytest.approx(2.0 * 0.01, rel=1e-9)


JC = {"model": "johnson_cook", "density": 8000.0, "youngs_modulus": 2.0e11, "poisson_ratio": 0.3,
      "A": 2.0e8, "B": 0.0, "n": 1.0, "C": 0.0, "reference_strain_rate": 1.0, "m": 1.0,
      "room_temperature": 300.0, "melt_temperature": 1.0e9, "specific_heat": 500.0, "taylor_quinney": 0.9}


def _squeezed(conductivity: float) -> ExplicitMPM:
    """A Johnson-Cook block squeezed plastically between two platens (velocity conditions),
    with the melt temperature so far up that heating does not soften it."""
    data = scene(dim=2, material={**JC, "thermal_conductivity": conductivity} if conductivity else JC)
    data["grid"] = {"lower": [0.0, 0.0], "upper": [1.0, 1.2], "cell_size": 0.1}
    data["boundary_conditions"] = [
        {"type": "velocity", "where": {"type": "box", "lower": [0.0, 1.0], "upper": [1.0, 1.2]}, "velocity": [0.0, -50.0]},
        {"type": "wall", "face": "y-", "mode": "stick"}]
    sim = ExplicitMPM(load_scene(data))
    for _ in range(300):
        sim.advance(1e-6)
    return sim


def test_the_heat_of_plastic_work_is_conducted():
    """Conduction moves the Taylor-Quinney heat, and creates or destroys none of it: the
    heat the particles hold, sum m c (T - T0), is the adiabatic run's (the mechanics are
    the same but for round-off: the heat does not soften a metal melting at 1e9 K), and
    the conducted field is smoother."""
    adiabatic, conducted = _squeezed(0.0), _squeezed(4.0e8)
    heat = []
    for sim in (adiabatic, conducted):
        p = sim.particles
        heat.append(float(np.sum(p.mass * JC["specific_heat"] * (p.extra["temperature"] - 10.0))))
    assert heat[0] > 0
    assert heat[1] == pytest.approx(heat[0], rel=1e-6)
    assert np.ptp(conducted.particles.extra["temperature"]) < np.ptp(adiabatic.particles.extra["temperature"])


@pytest.mark.parametrize("scheme", ["usl", "usf"])
def test_every_scheme_conducts_as_musl_where_nothing_moves(scheme):
    """The thermal hook sits at the same named points in every scheme: with the particles
    at rest the temperatures are MUSL's, bit for bit."""
    temperatures = []
    for name in ("musl", scheme):
        data = scene(conditions=[{"type": "temperature", "face": "x+", "temperature": 30.0},
                                 {"type": "convection", "face": "x-", "coefficient": 1.0, "ambient": 0.0}],
                     method={"scheme": name})
        sim = ExplicitMPM(load_scene(data))
        for _ in range(100):
            sim.advance(5e-3)
        temperatures.append(sim.particles.extra["temperature"].copy())
    assert np.array_equal(temperatures[0], temperatures[1])
    assert np.ptp(temperatures[0]) > 1.0


def test_johnson_cook_softens_with_the_conducted_temperature():
    """A Johnson-Cook bar at room temperature (300 K), its ends held at 800 K, heats by
    conduction for 0.5 ms and is then squeezed (m = 1, no hardening, no plastic heat):
    every particle that flows does so at A (1 - T*) with T* = (T_p - T_room)/(T_melt -
    T_room) of its conducted temperature, to round-off (the return maps the von Mises
    stress onto the flow stress exactly), and none is above it."""
    jc = {**JC, "melt_temperature": 1300.0, "taylor_quinney": 0.0, "thermal_conductivity": 1.0e9}
    data = scene(material=jc, conditions=[
        {"type": "temperature", "face": "x-", "temperature": 800.0},
        {"type": "temperature", "face": "x+", "temperature": 800.0},
        {"type": "velocity", "where": {"type": "box", "lower": [0.99], "upper": [1.1]},
         "velocity": ["where(t > 5e-4, -10, 0)"]},
        {"type": "wall", "face": "x-", "mode": "stick"}])
    data["bodies"][0]["initial_temperature"] = 300.0
    sim = ExplicitMPM(load_scene(data))
    for _ in range(900):
        sim.advance(1e-6)
    T = sim.particles.extra["temperature"]
    assert T.min() > 400.0 and T.max() < 1300.0   # heated, unevenly, not molten
    s = sim.particles.stress
    von_mises = np.abs(s[:, 0, 0] - s[:, 1, 1])   # uniaxial strain: sigma_yy = sigma_zz
    flow_stress = JC["A"] * (1.0 - (T - 300.0) / (1300.0 - 300.0))
    flowing = sim.particles.extra["plastic_strain_rate"] > 0   # yielded in the last step
    assert flowing.sum() >= 10   # the others unload in the reflected waves
    assert np.allclose(von_mises[flowing], flow_stress[flowing], rtol=1e-9, atol=0)
    assert np.all(von_mises <= flow_stress * (1 + 1e-9))


class TestContactExchange:
    """The heat exchange of contact "friction" node by node (solver/thermal_kernels.py): where
    the bodies touch, their fields take one C-weighted temperature and the deposited
    frictional heat, and sum_f C_f T_f changes by exactly that heat (round-off)."""

    def nodes(self, rng, n=400, fields=3):
        heat = np.zeros((fields * n, 3))
        heat[:, 0] = rng.uniform(0.0, 2.0, fields * n) * (rng.uniform(size=fields * n) > 0.2)   # some hold none
        touching = rng.uniform(size=n) > 0.5
        return heat, touching, rng.uniform(250.0, 450.0, fields * n), n

    def test_sharing_keeps_the_heat_and_gives_one_temperature_at_touching_nodes(self):
        from solver import thermal_kernels
        heat, touching, T, n = self.nodes(np.random.default_rng(5))
        before = heat[:, 0] * T
        shared = T.copy()
        thermal_kernels.share_temperature(heat, touching, n, 1e-12, shared)
        held = (heat[:, 0] > 1e-12).reshape(-1, n)
        after = heat[:, 0] * shared
        assert abs(after.sum() - before.sum()) <= 1e-13 * before.sum()
        per_node = (after - before).reshape(-1, n).sum(axis=0)
        assert np.abs(per_node).max() <= 1e-13 * np.abs(before).max()   # kept node by node
        grid = shared.reshape(-1, n)
        for i in np.flatnonzero(touching & (held.sum(axis=0) > 1)):
            values = grid[held[:, i], i]
            assert np.ptp(values) <= 1e-12 * values.max()
        untouched = ~touching[None, :] | ~held
        assert np.array_equal(grid[untouched], T.reshape(-1, n)[untouched])   # elsewhere as it was

    def test_deposited_friction_heat_enters_the_thermal_energy_exactly(self):
        from solver import thermal_kernels
        rng = np.random.default_rng(6)
        heat, touching, T, n = self.nodes(rng)
        added = rng.uniform(0.0, 1e-3, T.size)
        total = added.sum()
        new = T.copy()
        lost = thermal_kernels.deposit_heat(heat, touching, n, 1e-12, added, new)
        assert not added.any()   # taken
        gain = float(np.sum(heat[:, 0] * (new - T)))
        assert lost > 0.0   # (nodes without capacity: a body that holds no heat)
        assert gain + lost == pytest.approx(total, rel=1e-12)
