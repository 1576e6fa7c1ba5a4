"""The registries: a material from outside the package is one module (this one),
and the scene, its JSON schema, the capabilities, the output fields and the
documentation follow the registries.

The test material is a "spring": a Hookean bar in uniaxial stress,
sigma_xx += stiffness L_xx dt, with its strain as per-particle state and output.
"""
import json
import math
import re
import subprocess
import sys
from pathlib import Path
from typing import Literal

import numpy as np
import pytest

from solver import capabilities, fields, materials, run, shape
from solver import scene as solver_scene
from solver.materials import MaterialType, StateVariable
from solver.results import read_frame, read_series
from solver.scene import Scene, SceneError
from solver.scene_checks import load_scene
from solver.schema import BaseMaterial, ElasticMaterial, Positive
from solver.summary import summarize
from solver.thermal_schema import THERMAL_KEYS

DOCS = Path(__file__).parents[2] / "docs" / "scene.md"


class Spring(BaseMaterial):
    """A Hookean bar (1D): stress = stiffness * strain."""

    model: Literal["spring"]
    density: Positive
    stiffness: Positive

    def dilatational_wave_speed(self) -> float:
        return math.sqrt(self.stiffness / self.density)


class SpringModel:
    def __init__(self, config: Spring, dimension: int):
        self.stiffness = config.stiffness
        self.wave_speed = config.dilatational_wave_speed()

    def update_stress(self, particles, sl: slice, dt: float) -> None:
        rate = particles.L[sl, 0, 0]
        particles.stress[sl, 0, 0] += self.stiffness * rate * dt
        particles.extra["spring_strain"][sl] += rate * dt

    def particle_strain_energy(self, particles, sl: slice) -> np.ndarray:
        return particles.volume[sl] * particles.stress[sl, 0, 0] ** 2 / (2 * self.stiffness)

    def strain_energy(self, particles, sl: slice) -> float:
        return float(self.particle_strain_energy(particles, sl).sum())


SPRING = MaterialType(schema=Spring, solver_class=SpringModel,
                      state=(StateVariable("spring_strain", output=True),))

RATE, STIFFNESS, DENSITY, CELL, END = 0.1, 100.0, 1.0, 0.05, 0.01   # strain rate 1/s; c = 10 m/s


def stretched_bar() -> dict:
    """A spring bar on [0.25, 0.75] stretched at the strain rate RATE: initial velocity
    RATE (x - 0.5), the nodes at both ends moving with it (no unloading wave)."""
    end_speed = RATE * 0.25
    return {
        "name": "spring-bar", "dimension": 1,
        "grid": {"lower": [0.0], "upper": [1.0], "cell_size": CELL},
        "materials": {"bar": {"model": "spring", "density": DENSITY, "stiffness": STIFFNESS}},
        "bodies": [{"name": "bar", "material": "bar", "geometry": {"type": "box", "lower": [0.25], "upper": [0.75]},
                    "initial_velocity": [f"{RATE} * (x - 0.5)"]}],
        "boundary_conditions": [
            {"type": "velocity", "where": {"type": "box", "lower": [-1.0], "upper": [0.26]}, "velocity": [-end_speed]},
            {"type": "velocity", "where": {"type": "box", "lower": [0.74], "upper": [2.0]}, "velocity": [end_speed]},
        ],
        "time": {"end": END},
        "output": {"frames": 2, "fields": ["position", "stress", "spring_strain"]},
    }


@pytest.fixture
def spring():
    with materials.registered(SPRING):
        yield


def errors_of(scene: dict) -> list[dict]:
    with pytest.raises(SceneError) as caught:
        load_scene(json.dumps(scene))
    return caught.value.errors


class TestRegisteredMaterial:
    def test_the_scene_accepts_it_from_json(self, spring):
        scene = load_scene(json.dumps(stretched_bar()))
        assert isinstance(scene.materials["bar"], Spring)
        assert "spring" in capabilities.MATERIAL_MODELS
        assert "spring_strain" in capabilities.OUTPUT_FIELDS

    def test_the_json_schema_describes_it(self, spring):
        schema = Scene.model_json_schema()
        union = schema["properties"]["materials"]["additionalProperties"]
        assert union["discriminator"]["mapping"]["spring"] == "#/$defs/Spring"
        assert set(schema["$defs"]["Spring"]["required"]) == {"model", "density", "stiffness"}

    def test_its_own_keys_are_validated_at_their_paths(self, spring):
        scene = stretched_bar()
        scene["materials"]["bar"].update(stiffness=-1.0, damping=0.1)
        del scene["materials"]["bar"]["density"]
        assert sorted((e["path"], e["message"]) for e in errors_of(scene)) == [
            ("materials.bar.damping", "unknown key (not part of the scene format)"),
            ("materials.bar.density", "required"),
            ("materials.bar.stiffness", "must be > 0"),
        ]

    def test_a_stretched_bar_carries_the_stress_of_its_law(self, spring, tmp_path):
        """sigma = stiffness * RATE * t in the whole bar: the end nodes move with the
        stretch, so no wave unloads it. The bar lengthens by the strain eps = RATE t,
        so the rate the particles see differs from RATE by O(eps) (RATE / (1 + eps),
        particles shifting off the nodes' symmetric positions): tolerance 2 eps."""
        result = run(json.dumps(stretched_bar()), tmp_path)
        assert result.status == "complete"
        frame = read_frame(result.result_path, -1)
        stress, strain = frame["fields"]["stress"][:, 0], frame["fields"]["spring_strain"]
        eps = RATE * frame["time"]
        assert frame["time"] == pytest.approx(END, rel=1e-12)
        np.testing.assert_allclose(stress, STIFFNESS * eps, rtol=2 * eps)
        # the written state is the model's: the same increments summed, to round-off
        np.testing.assert_allclose(strain * STIFFNESS, stress, rtol=1e-12)

    def test_its_wave_speed_sets_the_time_step(self, spring, tmp_path):
        """dt = cfl h / (c + |v|max), c = sqrt(stiffness / density): in the summary (the
        schema's wave speed, |v| sampled at the bar's ends) and in the run (the solver
        object's, |v| of the outermost particles, 0.2375 from the centre)."""
        c = math.sqrt(STIFFNESS / DENSITY)
        assert summarize(load_scene(stretched_bar())).dt == pytest.approx(0.5 * CELL / (c + RATE * 0.25), rel=1e-12)
        result = run(stretched_bar(), tmp_path)
        first_dt = read_series(result.result_path)["time"][1]
        assert first_dt == pytest.approx(0.5 * CELL / (c + RATE * 0.2375), rel=1e-12)


class TestRegistration:
    def test_nothing_leaks_out_of_the_block(self):
        with materials.registered(SPRING):
            assert "spring" in materials.names()
        assert "spring" not in materials.names() and "spring" not in capabilities.MATERIAL_MODELS
        assert "spring" not in Scene.model_json_schema()["$defs"]
        errors = {e["path"]: e["message"] for e in errors_of(stretched_bar())}
        assert errors == {
            "materials.bar.model": "unknown model 'spring'; expected one of 'linear_elastic', 'neo_hookean', "
                                   "'j2_plasticity', 'johnson_cook', 'drucker_prager', "
                                   "'mohr_coulomb', 'modified_cam_clay', 'fluid', 'ideal_gas', 'rigid'",
            "output.fields[2]": "unknown output field 'spring_strain'; known fields: "
                                + ", ".join(sorted(capabilities.OUTPUT_FIELDS)),
        }

    def test_a_name_is_registered_once(self, spring):
        with pytest.raises(ValueError, match="'spring' is already registered"):
            materials.register(SPRING)

    def test_the_schema_must_name_its_model(self):
        class Nameless(BaseMaterial):
            density: Positive

        with pytest.raises(TypeError, match='must declare model: Literal'):
            materials.register(MaterialType(schema=Nameless, solver_class=SpringModel))

    def test_a_shared_state_variable_is_one_array(self):
        """temperature is NaN on particles of materials without it (johnson_cook's
        declaration): another material may not make it 0 there."""
        class Warm(Spring):
            model: Literal["warm"]

        warm = MaterialType(schema=Warm, solver_class=SpringModel,
                            state=(StateVariable("temperature", output=True),))
        with pytest.raises(ValueError, match="state 'temperature' differs from that of johnson_cook"):
            materials.register(warm)
        assert "warm" not in materials.names()

    def test_the_scene_stays_free_of_numba(self):
        """The service validates and summarizes scenes without loading numba: the
        registries' declarations must not import their kernels."""
        code = ("import sys; from solver.scene_checks import load_scene; from solver.summary import summarize; "
                "summarize(load_scene('examples/two_disks.json')); print('numba' in sys.modules)")
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                             cwd=Path(__file__).parents[2])
        assert out.stdout.strip() == "False"


    def test_the_schema_imports_no_checks_and_names_where_load_scene_is(self):
        """solver.scene is the schema alone (the size and stability checks sit above it, in
        solver.scene_checks); an old `from solver.scene import load_scene` is told the new place."""
        code = ("import sys; import solver.scene; print('solver.scene_checks' in sys.modules)\n"
                "try:\n    from solver.scene import load_scene\n"
                "except ImportError as error:\n    print(error)")
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                             cwd=Path(__file__).parents[2])
        imported_checks, message = out.stdout.splitlines()
        assert imported_checks == "False"
        assert "from solver.scene_checks import load_scene" in message

    def test_the_scene_module_still_names_the_registered_materials_schemas(self):
        assert solver_scene.NeoHookean is materials.REGISTRY["neo_hookean"].schema
        with pytest.raises(AttributeError, match="no attribute 'NoSuchModel'"):
            solver_scene.NoSuchModel


class TestBuiltFromTheRegistries:
    def test_output_fields_are_the_fields_module_and_the_materials_state(self):
        assert set(capabilities.OUTPUT_FIELDS) == set(fields.FIELDS) | set(materials.output_fields())
        assert materials.output_fields() == pytest.approx(
            {"plastic_strain": 0.0, "damage": 0.0, "temperature": math.nan, "yield_state": 0.0, "internal_energy": 0.0,
             "preconsolidation_pressure": 0.0},
            nan_ok=True)

    def test_shape_function_values_are_the_registry(self):
        method = Scene.model_json_schema()["$defs"]["Method"]["properties"]["shape_function"]
        assert method["enum"] == list(shape.REGISTRY) == ["linear", "gimp", "cpgimp", "cubic_bspline",
                                                           "quadratic_bspline", "bernstein", "cpdi_r4", "cpdi_q4", "cpdi_tet4"]
        assert set(capabilities.SHAPE_FUNCTIONS) == set(shape.REGISTRY)

    def test_a_capability_can_still_be_withdrawn(self, monkeypatch):
        monkeypatch.setattr(capabilities, "MATERIAL_MODELS", capabilities.MATERIAL_MODELS - {"neo_hookean"})
        scene = stretched_bar()
        scene["materials"]["bar"] = {"model": "neo_hookean", "density": 1.0, "youngs_modulus": 1.0,
                                     "poisson_ratio": 0.3}
        del scene["output"]
        assert errors_of(scene) == [{"path": "materials.bar.model", "message": "'neo_hookean' is not supported yet"}]


class TestDocumentation:
    """docs/scene.md describes every registered material and shape function."""

    def table_rows(self, header: str) -> dict[str, list[str]]:
        text = DOCS.read_text(encoding="utf-8")
        table = text[text.index(header):].split("\n\n", 1)[0]
        rows = {}
        for line in table.splitlines()[2:]:
            cells = [cell.strip() for cell in line.strip("|").split("|")]
            rows[cells[0].strip("`")] = cells[1:]
        return rows

    def test_every_material_is_in_the_table_with_its_keys(self):
        rows = self.table_rows("| model | keys (defaults in brackets) |")
        assert list(rows) == list(materials.names())
        elastic = set(ElasticMaterial.model_fields)
        for name, material in materials.REGISTRY.items():
            keys = {field.alias or key for key, field in material.schema.model_fields.items()} - {"model"}
            if "the elastic keys" in rows[name][0]:
                keys -= elastic
            keys -= set(THERMAL_KEYS)   # every material's: documented once, in the heat section
            keys -= {"pore_fluid"}      # every soil's: documented once, in its section
            documented = set(re.findall(r"`(\w+)`", rows[name][0]))
            assert keys <= documented, f"{name}: {sorted(keys - documented)} not in docs/scene.md"

    def test_the_thermal_keys_every_material_takes_are_documented(self):
        text = DOCS.read_text(encoding="utf-8")
        heat = text[text.index("## Heat"):].split("\n## ", 1)[0]
        assert set(THERMAL_KEYS) <= set(BaseMaterial.model_fields)
        for key in THERMAL_KEYS:
            assert f"`{key}`" in heat, f"{key} not in the heat section of docs/scene.md"

    def test_every_shape_function_is_in_the_table_with_its_support(self):
        rows = self.table_rows("| name | nodes per axis | what | grid ends |")
        assert {name: int(cells[0]) for name, cells in rows.items()} == {
            name: declared.support for name, declared in shape.REGISTRY.items()}
