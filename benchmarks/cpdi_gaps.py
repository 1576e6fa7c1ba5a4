"""E29 (review Fig. 25): the gaps and overlaps of CPDI-R4's parallelogram domains in a
compliant cantilever bent by a large gravity force, and CPDI-Q4's tracked quadrilaterals,
which have none; draws docs/images/<shape>_gaps_ppc<ppc>.png.

    python benchmarks/cpdi_gaps.py [--shape cpdi_q4] [--ppc 2]

A neo-Hookean bar 1.0 x 0.1 (E 1e5 Pa, nu 0.3, rho 1000), held by the nodes
at x <= 0.1, gravity 10 m/s^2 ramped over 1 s, local damping 0.3, 0.05 cells
and 2 particles per cell and axis (four across the bar), run to t = 3 (it hangs
nearly vertical). The domains are the `particle_domain` output field. Each
R4 parallelogram has its particle's exact area det F V0, so the domains' areas
add up to the body's; where neighbouring parallelograms overlap, the same area
is missing elsewhere as gaps (review Fig. 25: R4 cannot tile a bent body; Q4's
shared corners do). Printed: the overlap, 1 - (area of the union) / (sum of
the areas), from a raster of 2000 x 2000 points: 0 at t = 0 (the seeded boxes
tile the bar) to the raster's resolution, 5e-4.
"""
from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from solver import run  # noqa: E402
from solver.results import read_frame  # noqa: E402

SCENE = {
    "version": 1, "name": "E29: compliant cantilever under a large gravity force, cpdi_r4", "dimension": 2,
    "method": {"formulation": "ulmpm", "scheme": "musl", "shape_function": "cpdi_r4", "transfer": "flip"},
    "grid": {"lower": [0.0, -0.8], "upper": [1.2, 0.7], "cell_size": 0.05},
    "materials": {"soft": {"model": "neo_hookean", "density": 1000, "youngs_modulus": 1.0e5, "poisson_ratio": 0.3}},
    "bodies": [{"name": "beam", "material": "soft", "particles_per_cell": 1,
                "geometry": {"type": "box", "lower": [0.1, 0.45], "upper": [1.1, 0.55]}}],
    "boundary_conditions": [
        {"type": "velocity", "where": {"type": "box", "lower": [0.0, -0.8], "upper": [0.1, 0.7]},
         "velocity": [0, 0]}],
    "body_force": ["0", "-10 * min(t / 1.0, 1)"],
    "damping": {"type": "local", "coefficient": 0.3},
    "time": {"end": 3.0, "dt": None, "cfl": 0.5},
    "output": {"frames": 2, "fields": ["position", "particle_domain"]},
}


def overlap(corners: np.ndarray, n: int = 2000) -> float:
    """1 - area(union) / sum(areas) of the quadrilaterals (corners (p, 4, 2), axis-0-fastest order)."""
    from matplotlib.path import Path as Polygon
    ring = corners[:, [0, 1, 3, 2]]                       # counter-clockwise
    lo, hi = ring.reshape(-1, 2).min(axis=0), ring.reshape(-1, 2).max(axis=0)
    xs, ys = np.linspace(lo[0], hi[0], n), np.linspace(lo[1], hi[1], n)
    points = np.stack(np.meshgrid(xs, ys), axis=-1).reshape(-1, 2)
    covered = np.zeros(len(points), dtype=bool)
    for quad in ring:
        box = np.all((points >= quad.min(axis=0)) & (points <= quad.max(axis=0)), axis=1)
        covered[box] |= Polygon(quad).contains_points(points[box])
    cell = (xs[1] - xs[0]) * (ys[1] - ys[0])
    following = np.roll(ring, -1, axis=1)
    areas = 0.5 * np.abs(np.sum(ring[..., 0] * following[..., 1] - following[..., 0] * ring[..., 1], axis=1))
    return 1.0 - covered.sum() * cell / areas.sum()


def main() -> int:
    import argparse
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--shape", default="cpdi_r4", choices=["cpdi_r4", "cpdi_q4"])
    parser.add_argument("--ppc", type=int, default=2, help="particles per cell and axis")
    args = parser.parse_args()
    shape = args.shape
    SCENE["method"]["shape_function"] = shape
    SCENE["bodies"][0]["particles_per_cell"] = args.ppc
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.collections import PolyCollection

    with tempfile.TemporaryDirectory() as tmp:
        result = run(SCENE, Path(tmp) / "run")
        print(result.status, result.reason, result.message or "", f"{result.steps} steps")
        frames = [read_frame(result.result_path, i)["fields"] for i in (0, -1)]
    fig, axes = plt.subplots(2, 1, figsize=(9, 7), gridspec_kw={"height_ratios": [1, 3]})
    for ax, frame, title in zip(axes, frames, ("t = 0", "t = 3 s")):
        corners = frame["particle_domain"].reshape(-1, 4, 2)
        share = overlap(corners)
        print(f"{title}: overlap {share:.4f}")
        ax.add_collection(PolyCollection(corners[:, [0, 1, 3, 2]], facecolors="tab:blue", edgecolors="k",
                                         linewidths=0.3, alpha=0.5))
        ax.set_title(f"{shape} domains, {title}: overlaps (dark) = gaps, {100 * share:.1f} % of the area")
        ax.autoscale()
        ax.set_aspect("equal")
    fig.tight_layout()
    out = ROOT / "docs" / "images" / f"{shape}_gaps_ppc{args.ppc}.png"
    fig.savefig(out, dpi=110)
    print("wrote", out)
    return 0


if __name__ == "__main__":
    sys.exit(main())
