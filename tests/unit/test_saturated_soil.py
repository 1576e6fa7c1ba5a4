"""Saturated soil (solver/pore_fluid.py): validation of `pore_fluid`, `initial_pore_pressure`
and the `pore_pressure` conditions, nothing of it in a dry scene, the time step's limits,
the initial state (hydrostatic pressure, geostatic effective stress), the output fields, the
fused backend's step against the general one, and the memory the estimate counts."""
from __future__ import annotations

import numpy as np
import pytest

from solver import capabilities, fields, stability, summary
from solver.pore_fluid_schema import G_N
from solver.scene_checks import load_scene
from solver.stepper import ExplicitMPM
from tests.scene_errors import errors_of

WATER = {"bulk_modulus": 2.2e9, "density": 1000.0, "hydraulic_conductivity": 1.0e-8, "porosity": 0.5}
SOIL = {"model": "drucker_prager", "density": 2000.0, "youngs_modulus": 1.0e7, "poisson_ratio": 0.3,
        "friction_angle": 30.0, "cohesion": 0.0}


def scene(material=None, conditions=(), body=None, **top):
    out = {"dimension": 2, "grid": {"lower": [0.0, 0.0], "upper": [1.0, 2.0], "cell_size": 0.25},
           "materials": {"soil": dict(material or {**SOIL, "pore_fluid": WATER})},
           "bodies": [{"name": "soil", "material": "soil",
                       "geometry": {"type": "box", "lower": [0.0, 0.0], "upper": [1.0, 1.0]}, **(body or {})}],
           "boundary_conditions": list(conditions), "time": {"end": 0.01}}
    out.update(top)
    return out



class TestValidation:
    def test_a_pore_fluid_needs_a_soil_skeleton(self):
        water = {"model": "fluid", "density": 1000.0, "bulk_modulus": 2.2e9, "viscosity": 1e-3, "pore_fluid": WATER}
        [error] = errors_of(scene(material=water))
        assert error["path"] == "materials.soil.pore_fluid" and "'fluid'" in error["message"]

    def test_porosity_is_between_0_and_1(self):
        errors = errors_of(scene(material={**SOIL, "pore_fluid": {**WATER, "porosity": 1.0}}))
        assert errors[0]["path"] == "materials.soil.pore_fluid.porosity"

    @pytest.mark.parametrize("change, words", [
        ({"method": {"formulation": "tlmpm"}}, "formulation 'tlmpm'"),
        ({"method": {"scheme": "usf"}}, "scheme 'usf'"),
        ({"contact": {"model": "friction"}}, "contact model 'friction'"),
    ])
    def test_what_the_two_phase_step_does_not_run_is_refused_naming_the_pore_fluid(self, change, words):
        errors = errors_of(scene(**change))
        assert any(e["path"] == "materials.soil.pore_fluid" and words in e["message"] for e in errors), errors

    def test_a_pore_pressure_condition_needs_a_pore_fluid(self):
        [error] = errors_of(scene(material=SOIL, conditions=[{"type": "pore_pressure", "face": "y+", "pressure": 0}]))
        assert error == {"path": "boundary_conditions[0].type",
                         "message": "'pore_pressure' needs a material with a pore_fluid"}

    def test_a_pore_pressure_condition_takes_a_face_or_a_box(self):
        errors = errors_of(scene(conditions=[{"type": "pore_pressure", "pressure": 0}]))
        assert errors[0]["path"] == "boundary_conditions[0]" and "face or where" in errors[0]["message"]
        load_scene(scene(conditions=[{"type": "pore_pressure", "pressure": "1e3 * t",
                                      "where": {"type": "box", "lower": [0, 0.9], "upper": [1, 1.1]}}]))

    def test_an_initial_pore_pressure_needs_a_pore_fluid_and_its_keys(self):
        errors = errors_of(scene(material=SOIL, body={"initial_pore_pressure": {"type": "uniform", "pressure": 1}}))
        assert errors == [{"path": "bodies[0].initial_pore_pressure", "message": "material 'soil' has no pore_fluid"}]
        errors = errors_of(scene(body={"initial_pore_pressure": {"type": "hydrostatic"}}))
        assert errors[0]["path"] == "bodies[0].initial_pore_pressure.water_table"

    def test_the_time_step_counts_the_fluid_in_the_wave_and_its_diffusion(self):
        data = scene(material={**SOIL, "pore_fluid": {**WATER, "hydraulic_conductivity": 1.0}})
        loaded = load_scene(data)
        limit = stability.stable_limit(loaded)
        # D = k K_w / (n rho_w g_n); 2D, h = 0.25: h^2 / (4 D)
        diffusion = 0.25**2 / (4 * 1.0 * 2.2e9 / (0.5 * 1000.0 * G_N))
        assert limit.dt == pytest.approx(diffusion, rel=1e-12) and "diffusion" in limit.reason
        wave = stability.wave_limit(load_scene(scene()))
        lam_2mu = 1.0e7 * 0.7 / (1.3 * 0.4)
        assert wave.dt == pytest.approx(0.25 / np.sqrt((lam_2mu + 4.4e9) / 2000.0), rel=1e-12)


class TestState:
    def test_a_dry_scene_has_no_pore_state_and_steps_fused(self):
        sim = ExplicitMPM(load_scene(scene(material=SOIL)))
        assert sim.pore_fluid is None and "pore_pressure" not in sim.particles.extra
        assert sim.fused

    def test_hydrostatic_pressure_and_geostatic_effective_stress(self):
        data = scene(body={"initial_pore_pressure": {"type": "hydrostatic", "water_table": 1.5},
                           "initial_stress": {"type": "geostatic", "k0": 0.5}}, gravity=[0.0, -9.81])
        sim = ExplicitMPM(load_scene(data))
        p = sim.particles
        pore = p.extra["pore_pressure"]
        assert np.allclose(pore, 1000.0 * 9.81 * (1.5 - p.x[:, 1]))
        depth = 1.0 - p.x[:, 1]
        # under water: sigma'_v = -(rho_sat - rho_w) g d, sigma'_h = k0 sigma'_v
        assert np.allclose(p.stress[:, 1, 1], -(2000.0 - 1000.0) * 9.81 * depth)
        assert np.allclose(p.stress[:, 0, 0], 0.5 * p.stress[:, 1, 1])
        total = fields.field("stress")(sim)
        assert np.allclose(total[:, 1], -2000.0 * 9.81 * depth - 1000.0 * 9.81 * 0.5)   # the water above too
        assert np.allclose(fields.field("effective_stress")(sim)[:, 1], p.stress[:, 1, 1])
        assert np.array_equal(fields.field("pore_pressure")(sim), pore)

    def test_a_soil_at_rest_under_its_water_table_stays_near_rest(self):
        """Hydrostatic pore pressure and geostatic effective stress balance gravity: damped, the
        column settles with its pore pressure within rho_w g h (one cell's head) of the start.
        Not closer: the drained top node brings the projection of the top cell's particles to
        its held value, which a linear field's projection is not (an O(h) error at drained faces,
        docs/scene.md); measured 0.72 rho_w g h, the mean moving by 0.1 %."""
        data = scene(body={"initial_pore_pressure": {"type": "hydrostatic", "water_table": 1.0},
                           "initial_stress": {"type": "geostatic", "k0": 0.5}}, gravity=[0.0, -9.81],
                     conditions=[{"type": "wall", "face": f, "mode": "slip"} for f in ("x-", "x+", "y-")]
                     + [{"type": "pore_pressure", "face": "y+", "pressure": 0.0}],
                     damping={"type": "local", "coefficient": 0.5})
        data["grid"]["upper"] = [1.0, 1.0]
        sim = ExplicitMPM(load_scene(data))
        start = sim.particles.extra["pore_pressure"].copy()
        for _ in range(400):
            sim.advance(sim.stable_time_step(0.5))
        moved = sim.particles.extra["pore_pressure"] - start
        head = 1000.0 * 9.81
        assert np.max(np.abs(moved)) < head * 0.25
        assert abs(np.mean(moved)) < 0.005 * head * 0.5   # (the mean start pressure is head * 0.5)
        assert np.max(np.abs(sim.particles.v)) < 1e-6


class TestFrames:
    def test_every_field_formed_in_blocks_of_rows_is_the_field_formed_whole(self, monkeypatch):
        """solver/fields.py FrameFields.blocks: a field of each particle's own state is formed
        ROW_BLOCK rows at a time (here 7, which leaves a short last block); the total stress
        takes each row's pore pressure."""
        data = scene(body={"initial_pore_pressure": {"type": "hydrostatic", "water_table": 1.5},
                           "initial_stress": {"type": "geostatic", "k0": 0.5}}, gravity=[0.0, -9.81])
        data["output"] = {"fields": sorted(capabilities.ROW_LOCAL_FIELDS)}
        sim = ExplicitMPM(load_scene(data))
        sim.advance(sim.stable_time_step(0.5))
        monkeypatch.setattr(fields, "ROW_BLOCK", 7)
        frame = fields.frame_fields(sim, data["output"]["fields"])
        assert sim.particles.count % 7 != 0
        for name in capabilities.ROW_LOCAL_FIELDS:
            blocks = list(frame.blocks(name))
            assert [start for start, _ in blocks] == list(range(0, sim.particles.count, 7))
            assert np.array_equal(np.concatenate([values for _, values in blocks]), frame[name]), name


class TestBackends:
    @staticmethod
    def flowing(method: dict) -> dict:
        """A block falling towards a slip floor, drained along a box of nodes at its top and starting
        at 10 kPa, so that the flow, the squeeze and the force all act; half a cell clear of the
        grid's other ends (quadratic B-splines need it)."""
        fluid = {**WATER, "bulk_modulus": 1.0e7, "hydraulic_conductivity": 1.0e-3}
        data = scene(material={**SOIL, "cohesion": 1.0e3, "pore_fluid": fluid}, gravity=[0.0, -9.81],
                     body={"initial_pore_pressure": {"type": "uniform", "pressure": 1.0e4},
                           "geometry": {"type": "box", "lower": [0.1, 0.1], "upper": [0.9, 0.8]}},
                     conditions=[{"type": "wall", "face": "y-", "mode": "slip"},
                                 {"type": "pore_pressure", "where": {"type": "box", "lower": [0.0, 0.75],
                                                                     "upper": [1.0, 0.85]}, "pressure": 0.0}],
                     method=method)
        data["grid"] = {"lower": [0.0, 0.0], "upper": [1.0, 1.0], "cell_size": 0.1}
        return data

    @pytest.mark.parametrize("method", [{"scheme": "musl", "shape_function": "linear"},
                                        {"scheme": "usl", "shape_function": "quadratic_bspline", "transfer": "pic"}])
    def test_a_saturated_soil_steps_fused_and_gives_the_general_backends_answer(self, method):
        """The fused backend's pore passes form each particle's weights at x_p^t, the general
        backend's read them stored: the same weights to the bit (solver/pore_kernels.py). The
        mechanics' kernels differ in the order of some sums (tests/unit/test_fused.py): 1e-12
        relative after 100 steps, the bound test_fused holds them to."""
        loaded = load_scene(self.flowing(method))
        fused, general = ExplicitMPM(loaded), ExplicitMPM(loaded, general=True)
        assert fused.fused and not general.fused
        dt = fused.stable_time_step(0.5)
        for _ in range(100):
            fused.advance(dt)
            general.advance(dt)
        a, b = fused.particles, general.particles
        start = np.full(b.count, 1.0e4)
        assert np.max(np.abs(b.extra["pore_pressure"] - start)) > 1.0e3   # it drained and squeezed
        assert np.max(np.abs(b.v)) > 1e-3                                  # and moved
        for name in ("x", "v", "stress"):
            assert np.max(np.abs(getattr(a, name) - getattr(b, name))) <= 1e-12 * np.max(np.abs(getattr(b, name)))
        for name in ("pore_pressure", "darcy_flux"):
            assert np.max(np.abs(a.extra[name] - b.extra[name])) <= 1e-12 * np.max(np.abs(b.extra[name])), name
        assert fused.work["pore_pressure_work"] == pytest.approx(general.work["pore_pressure_work"], rel=1e-10)

    @pytest.mark.parametrize("general", [False, True])
    def test_the_memory_estimate_counts_the_pore_state(self, general):
        """Per particle: p, the Darcy flux (dim), three fluid constants, and on the fused backend the
        step's first positions (dim); per node: the six nodal arrays (solver/pore_fluid.py)."""
        method = {"shape_function": "gimp"} if general else {}
        wet, dry = load_scene(scene(method=method)), load_scene(scene(material=SOIL, method=method))
        assert summary.particle_bytes(wet) - summary.particle_bytes(dry) == 8 * (4 + 2 + (0 if general else 2))
        assert summary.node_bytes(wet, 1) - summary.node_bytes(dry, 1) == 8 * 6
