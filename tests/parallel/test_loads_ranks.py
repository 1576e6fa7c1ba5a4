"""Loads on several processes (issue 19): a traction and a force on a bar that crosses
the slab boundaries give the one-process particles on 2 processes.

The surface particles that carry the traction are found from the seeding lattice once,
before the particles are split into slabs, and each force load's particles share it by
their mass over the whole body: neither may depend on where the slabs are. As in
test_equivalence.py, the only difference between the runs is the order in which ghost
nodes' contributions are summed (round-off), hence 1e-12 relative.
"""
from __future__ import annotations

from ranks import last_frame, relative_difference, run_cli

TOLERANCE = 1e-12
BAR = {
    "name": "loads-ranks", "dimension": 2,
    "grid": {"lower": [0.0, 0.3], "upper": [1.2, 0.7], "cell_size": 0.025},
    "materials": {"m": {"model": "linear_elastic", "density": 1000, "youngs_modulus": 1e6, "poisson_ratio": 0.3}},
    "bodies": [{"name": "beam", "material": "m", "particles_per_cell": 2,
                "geometry": {"type": "polygon", "vertices": [[0.1, 0.45], [1.1, 0.45], [1.1, 0.55], [0.1, 0.55]]}}],
    "boundary_conditions": [{"type": "velocity", "where": {"type": "box", "lower": [0.0, 0.3], "upper": [0.1, 0.7]},
                             "velocity": [0, 0]}],
    "loads": [
        {"type": "traction", "body": "beam", "where": {"type": "box", "lower": [1.09, 0.4], "upper": [1.2, 0.6]},
         "traction": ["2e3 * min(t / 0.05, 1)", 0]},
        {"type": "force", "body": "beam", "where": {"type": "box", "lower": [0.5, 0.5], "upper": [0.9, 0.6]},
         "force": [0, "-3 * t"]},
    ],
    "time": {"end": 0.1, "dt": 2e-4},
    "output": {"frames": 2, "fields": ["position", "velocity", "stress"]},
    "parallel": {"processes": 1, "rebalance_every": 50},
}


def test_loads_on_two_processes_give_the_one_process_particles(tmp_path):
    single, double = tmp_path / "k1", tmp_path / "k2"
    for out, processes in ((single, 1), (double, 2)):
        finished = run_cli(BAR, out, processes)
        assert finished.returncode == 0, finished.stderr
    one, two = last_frame(single)["fields"], last_frame(double)["fields"]
    assert one["position"].shape == two["position"].shape
    for name in ("position", "velocity", "stress"):
        assert relative_difference(one[name], two[name]) < TOLERANCE, name
    assert abs(one["velocity"][:, 0]).max() > 1e-3   # the loads moved the bar: the comparison is not of a bar at rest
