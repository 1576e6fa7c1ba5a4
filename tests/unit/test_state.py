"""The particle state: every per-particle array is reachable by name and moves together."""
import numpy as np

from solver import kernels
from solver.examples import load_example
from solver.scene_checks import load_scene
from solver.state import make_grid, make_particles
from solver.summary import node_bytes


def _particles():
    particles, _ = make_particles(load_scene(load_example("two_disks")))
    return particles


def test_require_allocates_once_with_the_fill_value():
    p = _particles()
    t = p.require("temperature", fill=293.0)
    assert t.shape == (p.count,) and np.all(t == 293.0)
    t[0] = 500.0
    assert p.require("temperature")[0] == 500.0
    assert p.require("back_stress", (3, 3)).shape == (p.count, 3, 3)


def test_arrays_lists_core_and_extra_state():
    p = _particles()
    p.require("temperature")
    names = set(p.arrays())
    assert {"x", "v", "F", "L", "stress", "mass", "volume", "volume0", "id", "body"} <= names
    assert "extra/temperature" in names and "X" not in names


def test_take_reorders_every_array_consistently():
    p = _particles()
    p.require("temperature")[:] = np.arange(p.count)
    order = np.arange(p.count)[::-1][: p.count // 2]
    ids, x = p.id[order].copy(), p.x[order].copy()
    p.take(order)
    assert p.count == order.size
    assert np.array_equal(p.id, ids) and np.array_equal(p.x, x)
    assert np.array_equal(p.extra["temperature"], order.astype(float))
    assert all(a.shape[0] == order.size and a.flags.c_contiguous for a in p.arrays().values())


def test_a_deferred_array_is_brought_up_to_date_at_its_first_read_only():
    """Particles.defer: the update runs once, at the first read (also through arrays(), which
    checkpoints and migration use); stored() reads without it; an assignment drops it."""
    p = _particles()
    runs = []

    def update():
        runs.append(1)
        p.stored("stress")[:] = 7.0

    p.defer("stress", update)
    assert p.pending("stress") and np.all(p.stored("stress") == 0.0) and not runs
    assert np.all(p.stress == 7.0) and len(runs) == 1 and not p.pending("stress")
    assert np.all(p.stress == 7.0) and len(runs) == 1
    p.defer("stress", update)
    assert np.all(p.arrays()["stress"] == 7.0) and len(runs) == 2
    p.defer("stress", update)
    p.stress = np.zeros_like(p.stored("stress"))
    assert not p.pending("stress") and np.all(p.stress == 0.0) and len(runs) == 2


def test_the_grid_keeps_v_old_in_the_force_array_except_under_usf():
    """v_I^t takes f_I's array where nothing reads f_I after the update; USF forms v_I^t before the
    forces, so there each keeps its own. The grid holds what `mpm validate` counts a node (less the
    1-byte mask of active nodes)."""
    for scheme, shared in (("musl", True), ("usl", True), ("usf", False)):
        example = load_example("two_disks")
        scene = load_scene({**example, "method": {**example["method"], "scheme": scheme}})
        grid = make_grid(scene)
        assert (grid.v_old is grid.force) is shared, scheme
        held = {id(a): a.nbytes for a in (grid.mass, grid.momentum, grid.force, grid.v_old, grid.v_new)}
        assert sum(held.values()) == grid.n_nodes * (node_bytes(scene, threads=1) - 1), scheme


def test_the_grid_update_writes_v_old_over_the_force_node_by_node():
    """integrate_nodes reads f_I at a node before it writes v_I^t there: v_I^t and v~_I^{t+dt}
    are those formed from the nodal sums as they were (empty nodes at rest, no acceleration
    below the mass cut-off)."""
    rng = np.random.default_rng(7)
    n, dim, dt, cutoff = 200, 3, 0.01, 1e-3
    mass = rng.uniform(0.0, 2.0, n)
    mass[::17], mass[5::17] = 0.0, 1e-4   # empty nodes, and nodes below the cut-off
    momentum, force = rng.normal(size=(n, dim)), rng.normal(size=(n, dim))
    m = np.where(mass > 0.0, mass, 1.0)[:, None]
    v_old = np.where(mass[:, None] > 0.0, momentum / m, 0.0)
    v_new = np.where(mass[:, None] > cutoff, v_old + dt * force / m, v_old)
    force_then_v, out = force.copy(), np.empty((n, dim))
    kernels.integrate_nodes(kernels.axes(dim), dt, mass, momentum, force_then_v, cutoff, out)
    assert np.array_equal(force_then_v, v_old) and np.array_equal(out, v_new)
