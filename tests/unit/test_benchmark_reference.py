"""The speed reference of benchmarks/throughput.py computes what the solver computes."""
import sys
from pathlib import Path

import numpy as np

# benchmarks/ on the path only while these import: left there, its service.py would hide the
# service package from every later test in the same worker (test_docs loads every `mpm` command)
BENCHMARKS = str(Path(__file__).resolve().parents[2] / "benchmarks")
sys.path.insert(0, BENCHMARKS)
try:
    from reference_mpm2d import ReferenceMPM2D
    from throughput import block_scene
finally:
    sys.path.remove(BENCHMARKS)

from solver.scene_checks import load_scene  # noqa: E402
from solver.stepper import ExplicitMPM  # noqa: E402


def test_reference_matches_the_solver_step_for_step():
    scene = block_scene(2, 16)
    scene["time"]["dt"] = 1e-4
    sim = ExplicitMPM(load_scene(scene))
    ref = ReferenceMPM2D.from_simulation(sim)
    for _ in range(30):
        sim.advance(1e-4)
        ref.advance(1e-4)
    assert np.abs(sim.particles.stress).max() > 0     # the block is really straining
    np.testing.assert_allclose(ref.x, sim.particles.x, rtol=0, atol=1e-12)
    np.testing.assert_allclose(ref.v, sim.particles.v, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(ref.stress, sim.particles.stress, rtol=1e-9, atol=1e-9 * np.abs(ref.stress).max())
