"""The particle state: every per-particle array is reachable by name and moves together."""
import numpy as np

from solver.examples import load_example
from solver.scene_checks import load_scene
from solver.state import make_particles


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
