"""The contact correction node by node ([R] 5.2-5.7, spec A.8), and the contact's scene rules."""
import copy

import numpy as np
import pytest

from solver import contact
from solver.scene import SceneError
from solver.scene_checks import load_scene


def random_nodes(rng, n, fields, dim, rigid=None):
    """n nodes where every field has particles: masses, velocities and mass gradients."""
    mass = rng.uniform(0.1, 2.0, fields * n)
    v = rng.normal(size=(fields * n, dim))
    gradient = rng.normal(size=(fields * n, dim))
    is_rigid = np.zeros(fields, dtype=np.bool_)
    if rigid is not None:
        is_rigid[rigid] = True
        mass[rigid * n:(rigid + 1) * n] = 0.0   # rigid particles carry no mass
    return mass, mass.copy() + is_rigid.repeat(n), v, gradient, is_rigid   # presence > 0 everywhere


def correct(n, mass, presence, gradient, v, rigid, mu, record=True, rigid_velocity=None, heat=None):
    fields, dim = rigid.shape[0], v.shape[1]
    heat = np.zeros(0) if heat is None else heat
    impulse = np.zeros((fields, dim))
    pairs = np.zeros((fields, fields, 2))
    totals = np.zeros(2)
    velocity = np.zeros((fields, dim)) if rigid_velocity is None else rigid_velocity
    contact.correct_fields(n, mass, presence, gradient, v, rigid, velocity, np.full((fields, fields), mu), 1e-9, record,
                           np.ones(n, dtype=np.bool_), np.zeros(n), impulse, pairs, totals, heat)   # (volume 0: touch)
    return impulse, pairs, totals


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("mu", [0.0, 0.4, 10.0])
def test_correction_conserves_momentum_at_every_two_body_node(dim, mu):
    rng = np.random.default_rng(7)
    n = 500
    mass, presence, v, gradient, rigid = random_nodes(rng, n, 2, dim)
    before = mass[:n, None] * v[:n] + mass[n:, None] * v[n:]
    v_tilde = v.copy()
    correct(n, mass, presence, gradient, v, rigid, mu)
    after = mass[:n, None] * v[:n] + mass[n:, None] * v[n:]
    scale = np.abs(mass[:, None] * v_tilde).max()
    assert np.abs(after - before).max() < 1e-14 * scale
    assert np.any(v != v_tilde)   # (some nodes were in contact)


def test_correction_approach_release_and_friction_direction():
    rng = np.random.default_rng(3)
    n, dim = 400, 3
    mass, presence, v, gradient, rigid = random_nodes(rng, n, 2, dim)
    v_tilde = v.copy()
    mu = 0.3
    correct(n, mass, presence, gradient, v, rigid, mu)
    unit = gradient / np.linalg.norm(gradient, axis=1)[:, None]
    normal = unit[:n] - unit[n:]
    normal /= np.linalg.norm(normal, axis=1)[:, None]          # out of body 0, towards body 1
    v_cm = (mass[:n, None] * v_tilde[:n] + mass[n:, None] * v_tilde[n:]) / (mass[:n] + mass[n:])[:, None]
    dv = v_tilde[:n] - v_cm
    D = np.sum(dv * normal, axis=1)
    approach = D > 0
    # release ([R] 5.2): untouched
    assert np.array_equal(v[:n][~approach], v_tilde[:n][~approach])
    assert np.array_equal(v[n:][~approach], v_tilde[n:][~approach])
    # contact: the normal relative velocity is gone (Remark 31) ...
    rel_after = v[:n] - v[n:]
    assert np.abs(np.sum(rel_after * normal, axis=1)[approach]).max() < 1e-12
    # ... and the sliding keeps its direction and loses mu D at most (A.8: never reversed)
    slide_before = dv - D[:, None] * normal
    slide_after = (v[:n] - v_cm) - np.sum((v[:n] - v_cm) * normal, axis=1)[:, None] * normal
    sb, sa = np.linalg.norm(slide_before, axis=1)[approach], np.linalg.norm(slide_after, axis=1)[approach]
    expected = np.maximum(sb - mu * D[approach], 0.0)
    np.testing.assert_allclose(sa, expected, atol=1e-12)
    moving = expected > 0
    cos = np.sum(slide_before[approach][moving] * slide_after[approach][moving], axis=1) / (sb[moving] * sa[moving])
    np.testing.assert_allclose(cos, 1.0, atol=1e-12)


def test_rigid_field_takes_the_impulse_and_imposes_its_normal_velocity():
    rng = np.random.default_rng(11)
    n, dim = 300, 2
    mass, presence, v, gradient, rigid = random_nodes(rng, n, 2, dim, rigid=1)
    v_rigid = np.array([[0.0, 0.0], [0.5, -0.2]])
    v_tilde = v.copy()
    impulse, pairs, totals = correct(n, mass, presence, gradient, v, rigid, 0.0, rigid_velocity=v_rigid)
    normal = -gradient[n:] / np.linalg.norm(gradient[n:], axis=1)[:, None]   # the rigid surface's, into body 0
    D = np.sum((v_tilde[:n] - v_rigid[1]) * normal, axis=1)
    approach = D > 0
    # body 0 moves with the rigid body along the normal where it approached
    np.testing.assert_allclose(np.sum((v[:n] - v_rigid[1]) * normal, axis=1)[approach], 0.0, atol=1e-12)
    # the rigid body's impulse is what the material received (its reaction is the opposite)
    np.testing.assert_allclose(impulse[1], (mass[:n, None] * (v[:n] - v_tilde[:n])).sum(axis=0), rtol=1e-12)
    assert pairs[0, 1, 0] == pytest.approx(np.sum(mass[:n][approach] * D[approach]), rel=1e-12)
    assert np.array_equal(v[n:], v_tilde[n:])   # the rigid field itself is not changed


def test_record_off_changes_velocities_but_counts_nothing():
    rng = np.random.default_rng(5)
    n = 50
    mass, presence, v, gradient, rigid = random_nodes(rng, n, 2, 2)
    impulse, pairs, totals = correct(n, mass, presence, gradient, v, rigid, 0.5, record=False)
    assert not pairs.any() and not impulse.any() and not totals.any()


def test_friction_wall_stops_the_approach_and_limits_the_sliding():
    v = np.array([[1.0, -0.5], [1.0, 0.5], [0.1, -0.5]])    # into the wall y-, away, into with little sliding
    mass = np.ones(3)
    dissipated = np.zeros(1)
    heat = np.zeros(3)
    contact.friction_wall(np.arange(3), np.ones(3, dtype=np.int64), -np.ones(3), np.full(3, 0.4), v, mass,
                          dissipated, heat)
    np.testing.assert_allclose(v, [[1.0 - 0.4 * 0.5, 0.0], [1.0, 0.5], [0.0, 0.0]])
    assert dissipated[0] == pytest.approx(-(0.2 * 0.8))   # -m mu'D (slide - mu'D) of the sliding node
    assert heat.tolist() == [-dissipated[0], 0.0, 0.0]   # its heat, at its node (solver/thermal.py)


@pytest.mark.parametrize("rigid", [None, 1])
def test_the_frictional_heat_of_each_node_sums_to_the_frictional_work(rigid):
    rng = np.random.default_rng(11)
    n = 300
    mass, presence, v, gradient, is_rigid = random_nodes(rng, n, 2, 2, rigid)
    heat = np.zeros(2 * n)
    _, _, totals = correct(n, mass, presence, gradient, v, is_rigid, 0.3, heat=heat)
    assert totals[1] < 0 and np.all(heat >= 0)
    assert heat.sum() == pytest.approx(-totals[1], rel=1e-12)
    if rigid is not None:   # a rigid field holds no heat: all of it is the deformable body's
        assert not heat[n:].any()


# -- the scene -------------------------------------------------------------------------

BASE = {
    "version": 1, "dimension": 2,
    "grid": {"lower": [0, 0], "upper": [1, 1], "cell_size": 0.1},
    "materials": {"m": {"model": "linear_elastic", "density": 1, "youngs_modulus": 1, "poisson_ratio": 0.3}},
    "bodies": [{"name": "a", "material": "m", "geometry": {"type": "box", "lower": [0.1, 0.1], "upper": [0.4, 0.4]}},
               {"name": "b", "material": "m", "geometry": {"type": "box", "lower": [0.5, 0.5], "upper": [0.9, 0.9]}}],
    "time": {"end": 1},
}


def problems(contact_entry, **changes):
    scene = copy.deepcopy(BASE)
    scene["contact"] = contact_entry
    for key, value in changes.items():
        scene[key] = {**scene.get(key, {}), **value}
    with pytest.raises(SceneError) as error:
        load_scene(scene)
    return {e["path"]: e["message"] for e in error.value.errors}


def test_default_contact_is_the_single_field():
    assert load_scene(BASE).contact.model == "single_field"
    assert load_scene(BASE).grid_fields() == 1
    assert load_scene({**BASE, "contact": {"model": "friction"}}).grid_fields() == 2


def test_unknown_body_in_a_pair():
    found = problems({"model": "friction", "pairs": [{"bodies": ["a", "c"], "friction": 0.1}]})
    assert "unknown body 'c'" in found["contact.pairs[0].bodies"]


def test_pair_listed_twice():
    found = problems({"model": "friction", "pairs": [{"bodies": ["a", "b"], "friction": 0.1},
                                                     {"bodies": ["b", "a"], "friction": 0.2}]})
    assert "already listed (contact.pairs[0])" in found["contact.pairs[1].bodies"]


def test_pair_of_one_body():
    found = problems({"model": "friction", "pairs": [{"bodies": ["a", "a"], "friction": 0.1}]})
    assert "two different bodies" in found["contact.pairs[0].bodies"]


def test_negative_friction():
    assert problems({"model": "friction", "friction": -0.1})["contact.friction"] == "must be >= 0"
    found = problems({"model": "friction", "pairs": [{"bodies": ["a", "b"], "friction": -1}]})
    assert found["contact.pairs[0].friction"] == "must be >= 0"


def test_contact_with_tlmpm_is_refused():
    found = problems({"model": "friction"}, method={"formulation": "tlmpm"})
    assert "needs formulation 'ulmpm'" in found["contact.model"]


def test_friction_without_fields_is_refused():
    found = problems({"model": "single_field", "friction": 0.3})
    assert "use model 'friction'" in found["contact.model"]


def test_fields_beyond_memory_are_refused(monkeypatch):
    from solver import capabilities
    monkeypatch.setattr(capabilities, "MAX_CONTACT_FIELD_BYTES", 1000)
    found = problems({"model": "friction"})
    assert "velocity fields (one per body)" in found["contact.model"]


def test_density_normals_with_processes_are_accepted_and_widen_the_halo():
    # the cell densities cross the slabs (tests/parallel/test_equivalence.py "contact-density")
    from solver.contact import domain_support
    scene = copy.deepcopy(BASE)
    scene["contact"] = {"model": "friction", "normals": "density_gradient"}
    scene["parallel"] = {"processes": 2}
    assert domain_support(load_scene(scene), 2) == 4
    scene["contact"]["normals"] = "mass_gradient"
    assert domain_support(load_scene(scene), 2) == 2


def test_one_field_features_are_refused_with_a_field_per_body():
    """Absorbing faces, cpdi_q4 and cpdi_tet4 keep one grid field: refused, each at its path
    (conduction holds every field: tests/verification/test_heat_contact.py)."""
    scene = copy.deepcopy(BASE)
    scene["contact"] = {"model": "friction"}
    scene["boundary_conditions"] = [{"type": "absorbing", "face": "x+"}]
    with pytest.raises(SceneError) as error:
        load_scene(scene)
    found = {e["path"]: e["message"] for e in error.value.errors}
    assert "with contact 'friction'" in found["boundary_conditions[0].type"]
    found = problems({"model": "friction"}, method={"shape_function": "cpdi_q4"})
    assert "with contact 'friction'" in found["method.shape_function"]
    tetrahedra = {**BASE, "dimension": 3, "contact": {"model": "friction"}, "method": {"shape_function": "cpdi_tet4"},
                  "grid": {"lower": [0, 0, 0], "upper": [1, 1, 1], "cell_size": 0.1},
                  "bodies": [{**body, "geometry": {**body["geometry"], "lower": body["geometry"]["lower"] + [0.1],
                                                   "upper": body["geometry"]["upper"] + [0.4]}}
                             for body in BASE["bodies"]]}
    with pytest.raises(SceneError) as error:
        load_scene(tetrahedra)
    assert "with contact 'friction'" in {e["path"]: e["message"] for e in error.value.errors}["method.shape_function"]
    conducting = {"m": {**BASE["materials"]["m"], "thermal_conductivity": 1.0, "specific_heat": 1.0}}
    load_scene({**BASE, "contact": {"model": "friction"}, "materials": conducting})   # conduction: every field
    load_scene({**BASE, "method": {"shape_function": "cpdi_q4"}})
