"""What particle order costs: the step on particles in cell order against the same
particles shuffled (as they become after a long run of flow), side by side.

    python benchmarks/particle_order.py [--threads 1] [--repeats 3]

The block of benchmarks/throughput.py (2D 129,600 and 3D 140,608 particles) with
FLIP (linear, MUSL), APIC and MLS (quadratic B-splines, USL). Each method's block
is stepped in seeding order (which is cell order: the seeding lattice runs x
fastest, as the grid's node numbering does), then shuffled, then sorted by cell
again (`by_cell`: the order a sort every few steps would restore), alternating and
keeping the best of `repeats` rounds. The ratio shuffled / sorted is what sorting
the particles by cell would buy once they are mixed; sorted / seeded says whether
the sort itself keeps the seeding order's speed.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from throughput import MLS_DT, block_scene, mls_block_scene, rate  # noqa: E402

from solver.scene_checks import load_scene  # noqa: E402
from solver.stepper import ExplicitMPM  # noqa: E402

METHODS = {
    "FLIP (linear, MUSL)": lambda dim, cells, threads: {**block_scene(dim, cells), "parallel": {"threads": threads}},
    "APIC (quadratic, USL)": lambda dim, cells, threads: mls_block_scene(dim, cells, threads, "apic"),
    "MLS (quadratic, USL)": lambda dim, cells, threads: mls_block_scene(dim, cells, threads, "mls"),
}


def by_cell(sim: ExplicitMPM) -> np.ndarray:
    """The particles' order by the flat index of their cell (x fastest, as the nodes)."""
    g, x = sim.grid, sim.particles.x
    cell = np.clip(((x - g.lower) / g.h).astype(np.int64), 0, g.cells - 1)
    strides = np.concatenate(([1], np.cumprod(g.cells[:-1])))
    return np.argsort(cell @ strides, kind="stable")


def reorder(sim: ExplicitMPM, order: np.ndarray) -> None:
    sim.particles.take(order)
    sim.place()


def compare(dim: int, cells: int, steps: int, threads: int, repeats: int) -> list[dict]:
    import numba
    numba.set_num_threads(threads)
    rows = []
    for name, scene_of in METHODS.items():
        sims = {kind: ExplicitMPM(load_scene(scene_of(dim, cells, threads))) for kind in ("seeded", "shuffled", "sorted")}
        n = sims["seeded"].particles.count
        reorder(sims["shuffled"], np.random.default_rng(0).permutation(n))
        reorder(sims["sorted"], np.random.default_rng(0).permutation(n))
        reorder(sims["sorted"], by_cell(sims["sorted"]))
        for sim in sims.values():
            sim.advance(MLS_DT)
        best = {kind: 0.0 for kind in sims}
        for _ in range(repeats):
            for kind, sim in sims.items():
                best[kind] = max(best[kind], rate(sim, n, steps, MLS_DT))
        rows.append({"method": name, "dimension": dim, "particles": n, "threads": threads, **best})
        print(f"{dim}D {name:<24}{n:>9,} {threads} thr: seeded {best['seeded'] / 1e6:6.2f}  shuffled "
              f"{best['shuffled'] / 1e6:6.2f}  sorted {best['sorted'] / 1e6:6.2f} M particle-steps/s; "
              f"sorted/shuffled {best['sorted'] / best['shuffled']:.2f}, sorted/seeded "
              f"{best['sorted'] / best['seeded']:.2f}", flush=True)
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    for dim, cells, steps in ((2, 225, 10), (3, 32, 4)):
        compare(dim, cells, steps, args.threads, args.repeats)
    return 0


if __name__ == "__main__":
    sys.exit(main())
