"""What one pass over the particles per step would gain: the numba MLS reference with G2P
and the next step's P2G fused, against the same reference unfused (issue 18's idea
"fusing G2P with the next step's P2G", as Claymore does on GPUs).

    python benchmarks/transfer_fusion.py                 # 2D block of 129,600 particles, 1 and 2 threads
    python benchmarks/transfer_fusion.py --cells 112 --repeats 7

benchmarks/reference_mls.py's 2D step is P2G, grid, G2P: the particle arrays are read
twice a step (P2G reads x, v, C, F, m, V; G2P reads x, C, F and writes v, C, x, F). Fused,
one pass gathers particle p's new v, C from this step's grid, moves it, updates F, and
scatters it at once into the next step's grid (a second set of nodal arrays): each
particle's arrays are read once, and the new state never leaves the registers between
the two transfers. The same operations in the same order, so after N steps both give
the same bits (checked). The solver does not do this: its step ends with the particles
complete and the grid free for anything between steps (output, migration, a new dt,
hooks); this script measures what that costs at most.

Measured (docs/benchmarks.md at 735f9cb): the fused pass is not faster here,
its best step 0.88-0.97 of the unfused one's rate over three runs on a 2-core AMD EPYC
(pairs 0.82-1.18): the transfers are bound by their arithmetic and their nodal accesses,
not by reading the particle arrays twice.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numba
import numpy as np
from numba import njit, prange

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from reference_mls import (ReferenceMLS, deform_2d, gather_2d, node_velocity_2d, own_zeroed, p2g_2d,  # noqa: E402
                           scatter_2d)
from throughput import MLS_DT, mls_block_scene  # noqa: E402


@njit(parallel=True, cache=True)
def fused_2d(dt, inv_dx, nx, x, v, C, F, mass, vol, lam, mu, grid_mass, grid_mom, copies_mass, copies_mom,
             next_mass, next_mom, next_copies_mass, next_copies_mom):
    """The grid update of the P2G already in grid_*, then per particle G2P and the next P2G
    into next_*."""
    n = x.shape[0]
    threads = copies_mass.shape[0] + 1
    for node in prange(grid_mass.shape[0]):
        node_velocity_2d(node, grid_mass, grid_mom, copies_mass, copies_mom)
    for t in prange(threads):
        gm, gp = own_zeroed(t, next_mass, next_mom, next_copies_mass, next_copies_mom)
        for p in range((n * t) // threads, (n * (t + 1)) // threads):
            vx, vy, c00, c01, c10, c11 = gather_2d(dt, inv_dx, nx, x, v, C, grid_mom, p)
            deform_2d(dt, F, p, c00, c01, c10, c11)
            scatter_2d(dt, inv_dx, nx, x, v, C, F, mass, vol, lam, mu, gm, gp, p)


class FusedReference(ReferenceMLS):
    """ReferenceMLS stepped by `fused_2d`: the grid of the next step's P2G is filled at the end
    of each step, so the first step starts with a P2G alone."""

    def __init__(self, *args):
        super().__init__(*args)
        self.next = (np.zeros_like(self.grid_mass), np.zeros_like(self.grid_mom),
                     np.zeros_like(self.copies_mass), np.zeros_like(self.copies_mom))
        self.primed = False

    def advance(self, dt: float) -> None:
        current = (self.grid_mass, self.grid_mom, self.copies_mass, self.copies_mom)
        state = (dt, self.inv_dx, self.nx, self.x, self.v, self.C, self.F, self.mass, self.vol, self.lam, self.mu)
        if not self.primed:
            p2g_2d(*state, *current)
            self.primed = True
        fused_2d(*state, *current, *self.next)
        (self.grid_mass, self.grid_mom, self.copies_mass, self.copies_mom), self.next = self.next, current


def block(cells: int, threads: int) -> tuple:
    from solver.scene_checks import load_scene
    from solver.stepper import ExplicitMPM
    sim = ExplicitMPM(load_scene(mls_block_scene(2, cells, threads, "mls")))
    p, model = sim.particles, sim.materials[0][0]
    return p.x, p.v, p.mass, p.volume, cells, model.lam, model.mu, threads


def compare(cells: int, threads: int, steps: int, repeats: int) -> dict:
    numba.set_num_threads(threads)
    args = block(cells, threads)
    unfused, fused = ReferenceMLS(*args), FusedReference(*args)
    for ref in (unfused, fused):
        ref.advance(MLS_DT)
    same = np.array_equal(unfused.x, fused.x) and np.array_equal(unfused.F, fused.F)
    n = unfused.x.shape[0]
    times = {"unfused": [], "fused": []}
    for _ in range(repeats):   # alternating: both see the same load
        for name, ref in (("unfused", unfused), ("fused", fused)):
            start = time.perf_counter()
            for _ in range(steps):
                ref.advance(MLS_DT)
            times[name].append((time.perf_counter() - start) / steps / n * 1e9)
    same = same and all(np.array_equal(getattr(unfused, k), getattr(fused, k)) for k in ("x", "v", "C", "F"))
    best = {k: min(v) for k, v in times.items()}
    ratios = [u / f for u, f in zip(times["unfused"], times["fused"])]
    return {"particles": n, "threads": threads, "same_bits": bool(same), "ns_unfused": best["unfused"],
            "ns_fused": best["fused"], "speedup_best": best["unfused"] / best["fused"],
            "speedup_range": (min(ratios), max(ratios))}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--cells", type=int, default=225)
    parser.add_argument("--steps", type=int, default=15)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    args = parser.parse_args()
    print(f"{'particles':>10}{'threads':>9}{'same bits':>11}{'unfused ns/p':>14}{'fused ns/p':>12}"
          f"{'speed-up (best)':>17}{'range of pairs':>17}")
    for threads in args.threads:
        r = compare(args.cells, threads, args.steps, args.repeats)
        lo, hi = r["speedup_range"]
        print(f"{r['particles']:>10,}{threads:>9}{str(r['same_bits']):>11}{r['ns_unfused']:>14.1f}"
              f"{r['ns_fused']:>12.1f}{r['speedup_best']:>17.2f}{f'{lo:.2f}-{hi:.2f}':>17}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
