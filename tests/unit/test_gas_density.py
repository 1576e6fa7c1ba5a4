"""A gas's density from the grid (solver/gas_density.py, `ideal_gas` `density_from_grid`)."""
import numpy as np
import pytest

from solver.scene import SceneError
from solver.scene_checks import load_scene

GAMMA = 1.4


def gas_scene(dim=1, shape_function="linear", per_cell=2, cells=8, **gas):
    """A still gas filling the whole grid (a closed box), `cells` cells of 0.125 per axis."""
    upper = [1.0] * dim
    return {
        "dimension": dim,
        "method": {"shape_function": shape_function},
        "grid": {"lower": [0.0] * dim, "upper": upper, "cell_size": 1.0 / cells},
        "materials": {"air": {"model": "ideal_gas", "gamma": GAMMA, **gas}},
        "bodies": [{"name": "gas", "material": "air", "particles_per_cell": per_cell,
                    "geometry": {"type": "box", "lower": [0.0] * dim, "upper": upper},
                    "initial_density": 1.0, "initial_pressure": 1.0}],
        "time": {"end": 0.01},
    }


def simulation(scene):
    from solver.stepper import ExplicitMPM
    return ExplicitMPM(load_scene(scene))


def the_hook(sim):
    from solver.gas_density import GridDensity
    found = [h for h in sim.hooks._hooks if isinstance(h, GridDensity)]
    assert len(found) == 1
    return found[0]


@pytest.mark.parametrize("name", ["linear", "quadratic_bspline", "cubic_bspline", "bernstein"])
def test_the_nodes_volumes_are_the_integrals_of_their_functions(name):
    """sum_I V_I = the length particles may take (partition of unity: the grid's, less the half
    cell at each end that quadratic B-splines refuse); h inside, where every function is a
    translate of one of unit integral (Bernstein's alternate: 4h/3 at an element's ends, 2h/3 in
    its middle); the linear hat's end node has half its support: h/2."""
    from solver import shape
    from solver.gas_density import axis_integrals

    module, h, cells = shape.get(name), 0.25, 12
    v = axis_integrals(module, module.SUPPORT, -1.0, h, cells)
    refused = h if name == "quadratic_bspline" else 0.0
    assert v.sum() == pytest.approx(cells * h - refused, rel=1e-13)
    if name == "bernstein":
        assert v[2:-2] == pytest.approx(np.where(np.arange(2, cells - 1) % 2 == 0, 4 * h / 3, 2 * h / 3), rel=1e-13)
    else:
        assert v[3:-3] == pytest.approx(np.full(cells - 5, h), rel=1e-13)
    if name == "linear":
        assert v[[0, -1]] == pytest.approx([h / 2, h / 2], rel=1e-13)


def test_in_2d_a_node_s_volume_is_the_product_of_its_axes():
    from solver.gas_density import nodal_volumes
    sim = simulation(gas_scene(dim=2))
    v = nodal_volumes(sim).reshape(9, 9)   # (y, x): x fastest
    h = 0.125
    assert v.sum() == pytest.approx(1.0, rel=1e-13)
    assert v[4, 4] == pytest.approx(h * h, rel=1e-13)
    assert v[0, 4] == pytest.approx(h * h / 2, rel=1e-13)
    assert v[0, 0] == pytest.approx(h * h / 4, rel=1e-13)


@pytest.mark.parametrize("dim", [1, 2])
def test_a_gas_that_fills_its_box_evenly_keeps_its_volumes(dim):
    """Particles that tile the box with the mass they were seeded with: the grid's density is
    theirs, so the reset changes nothing (to round-off) and does no work."""
    sim = simulation(gas_scene(dim=dim))
    p = sim.particles
    volume, energy = p.volume.copy(), p.extra["internal_energy"].copy()
    the_hook(sim).begin_step(sim, 1e-3)
    assert p.volume == pytest.approx(volume, rel=1e-12)
    assert p.extra["internal_energy"] == pytest.approx(energy, rel=1e-12)
    assert abs(sim.work["gas_density_work"]) < 1e-12 * float((p.mass * energy).sum())


@pytest.mark.parametrize("dim", [1, 2])
def test_drifted_volumes_go_back_to_the_room_the_particles_take_along_the_adiabat(dim):
    """Volumes J V0 off by up to 30 % (what cell-crossing leaves in an expanded gas) return to
    the seeded ones, which depend on the positions and masses alone; each particle's p V^gamma
    is kept, the stress carries the new pressure, J = V / V0, and the work booked is the
    internal energy the gas gained."""
    sim = simulation(gas_scene(dim=dim))
    p = sim.particles
    seeded = p.volume.copy()
    drift = np.random.default_rng(5).uniform(0.7, 1.3, p.count)
    p.volume *= drift
    for a in range(dim):
        p.F[:, a, a] = drift ** (1.0 / dim)
    e = p.extra["internal_energy"]
    e *= drift ** (1.0 - GAMMA)   # the drifted state on the same adiabat as the seeded one
    pressure = (GAMMA - 1.0) * p.mass * e / p.volume
    for a in range(3):
        p.stress[:, a, a] = -pressure
    before = float((p.mass * e).sum())
    the_hook(sim).begin_step(sim, 1e-3)
    assert p.volume == pytest.approx(seeded, rel=1e-12)
    new_pressure = (GAMMA - 1.0) * p.mass * e / p.volume
    assert new_pressure * p.volume**GAMMA == pytest.approx(pressure * (seeded * drift) ** GAMMA, rel=1e-12)
    assert new_pressure == pytest.approx(1.0, rel=1e-12)   # the seeded state's
    assert -p.stress[:, 0, 0] == pytest.approx(new_pressure, rel=1e-12)
    assert np.linalg.det(p.F) == pytest.approx(p.volume / p.volume0, rel=1e-12)
    assert sim.work["gas_density_work"] == pytest.approx(float((p.mass * e).sum()) - before, rel=1e-12)


def test_shape_functions_with_particle_domains_keep_the_particles_volumes():
    """GIMP's weights depend on each particle's size: no nodal integral, no hook by default."""
    from solver.gas_density import GridDensity
    sim = simulation(gas_scene(shape_function="gimp"))
    assert not [h for h in sim.hooks._hooks if isinstance(h, GridDensity)]
    assert "gas_density_work" not in sim.work.totals(sim.domain)


@pytest.mark.parametrize("change, words", [
    ({"method": {"shape_function": "gimp"}}, "weights of the position alone"),
    ({"method": {"shape_function": "linear", "formulation": "tlmpm"}}, "formulation 'ulmpm'"),
])
def test_asking_for_the_density_from_the_grid_where_it_is_not_defined_names_the_field(change, words):
    scene = {**gas_scene(density_from_grid=True), **change}
    with pytest.raises(SceneError) as error:
        load_scene(scene)
    assert "materials.air.density_from_grid" in str(error.value)
    assert words in str(error.value)
