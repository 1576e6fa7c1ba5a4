"""E7: the generalized vortex ([R] 6.2.3), TLMPM with quadratic Bernstein functions.

The ring 0.75 <= R <= 1.25 is twisted by x = Q(g(t) h(R)) X, g = sin(pi t), up to
a rotation of 1 rad at mid-radius and a shear of 7 at t = 0.5 s. The run starts
from the exact velocity and uses the corrected body force (F1); see
solver/manufactured.py. The CI version stops at t = 0.5 s, the peak of the
motion, where [R] Fig. 75 compares the deformed ring with the analytic map.

[R] Fig. 74 reports order 2 at the coarse meshes, falling off as h decreases
until the error plateaus; VERIFICATION_CASES E7 suggests a local slope of at
least 1.5 over the first refinements, the issue 1.8. h here is the cell size,
half a Bernstein element (solver/shape/kernels/bernstein.py); 0.1 and 0.05 are the two
coarsest levels on which the ring is resolved (at 0.2, 2.5 cells across it, a
particle inverts). Pure FLIP as in [R] §6 by default: with the blend 0.99 the PIC
share damps the motion a little every step, and the vortex takes 8 times more
steps per cell than E5/E6 (its time step is limited by the stretch), so that
damping dominates: the order from 0.1 to 0.05 is 1.5 with 0.99 and 1.9 with 1.0.
"""
import numpy as np
import pytest

from mpm_cases import run_scene

from solver.manufactured import Options, vortex_angle, vortex_displacement, vortex_scene
from solver.norms import errors_of_result, observed_orders

LEVELS = [0.1, 0.05]
PEAK = 0.5


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    out = {}
    for h in LEVELS:
        scene = vortex_scene(h, Options(shape="bernstein", flip_ratio=1.0, frames=11), end=PEAK)
        out[h] = run_scene(scene, tmp_path_factory.mktemp(f"vortex{round(1 / h)}"))
        assert out[h].result.status == "complete", out[h].result.message
    return out


def test_bernstein_order_over_the_coarse_meshes(runs):
    e2 = [errors_of_result(runs[h].path, vortex_displacement).e2 for h in LEVELS]
    assert e2[1] < e2[0]
    assert observed_orders(LEVELS, e2)[0] >= 1.8, e2


def test_deformed_ring_matches_the_analytic_map(runs):
    """At t = 0.5 s the particles lie where the exact map puts them. [R] Fig. 75 shows
    the agreement only as a picture (h = 0.033); our reading of "the same picture":
    the rms distance to the exact positions is below 10 % of the rms displacement,
    and every particle has turned about the centre by the exact alpha(R) to within
    0.1 rad, a tenth of the peak rotation (1 rad at mid-radius)."""
    first, last = runs[0.05].frame(0), runs[0.05].frame(-1)
    assert last["time"] == pytest.approx(PEAK)
    X = first["fields"]["position"][np.argsort(first["fields"]["id"])]
    x = last["fields"]["position"][np.argsort(last["fields"]["id"])]
    u = vortex_displacement(X, PEAK)
    miss = np.sum((x - X - u) ** 2, axis=1)
    assert np.sqrt(miss.mean() / np.sum(u**2, axis=1).mean()) < 0.1
    turned = np.angle((x[:, 0] + 1j * x[:, 1]) / (X[:, 0] + 1j * X[:, 1]))
    assert np.max(np.abs(turned - vortex_angle(np.hypot(X[:, 0], X[:, 1]), PEAK))) < 0.1
