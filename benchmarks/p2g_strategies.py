"""Race-free P2G, two ways, measured side by side (issue 9) -> docs/benchmarks.md.

    python benchmarks/p2g_strategies.py [--quick]

1. per-thread copies (what the solver does, solver/fused.py): each thread adds
   its block of particles into its own copy of the nodal arrays; the copies are
   summed node by node afterwards.
2. coloured cell blocks: each step the particles are binned by cell with a
   counting sort, cells are grouped into blocks of 4 x 4, and the blocks are
   processed in 4 colours (block parity per axis): blocks of one colour are at
   least 4 cells apart, wider than a quadratic B-spline stencil reaches, so the
   threads add straight into the one grid.

Both compute the same nodal mass, momentum and force as the solver's P2G of
the same 2D elastic block (quadratic B-splines, APIC); the table gives the time
per particle of each and checks that their grids agree to round-off.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np
from numba import njit, prange

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from throughput import mls_block_scene  # noqa: E402

from solver import fused  # noqa: E402
from solver.scene_checks import load_scene  # noqa: E402
from solver.stepper import ExplicitMPM  # noqa: E402

BLOCK = 4   # cells per block side


@njit(cache=True)
def bin_by_cell(x, lower, inv_h, cells, order, starts):
    """Counting sort of the particles by cell (x fastest): order[starts[c]:starts[c+1]] are cell c's."""
    n_cells = cells[0] * cells[1]
    counts = np.zeros(n_cells + 1, dtype=np.int64)
    cell_of = np.empty(x.shape[0], dtype=np.int64)
    for p in range(x.shape[0]):
        i = min(int((x[p, 0] - lower[0]) * inv_h[0]), cells[0] - 1)
        j = min(int((x[p, 1] - lower[1]) * inv_h[1]), cells[1] - 1)
        cell_of[p] = i + cells[0] * j
        counts[cell_of[p] + 1] += 1
    for c in range(n_cells):
        counts[c + 1] += counts[c]
    starts[:] = counts
    fill = counts[:-1].copy()
    for p in range(x.shape[0]):
        c = cell_of[p]
        order[fill[c]] = p
        fill[c] += 1


@njit(parallel=True, cache=True)
def coloured_p2g(x, v, C, mass, volume, stress, lower, h, inv_h, cells, strides, order, starts,
                 grid_mass, grid_mom, grid_force):
    blocks_x = (cells[0] + BLOCK - 1) // BLOCK
    blocks_y = (cells[1] + BLOCK - 1) // BLOCK
    for colour in range(4):
        cx, cy = colour % 2, colour // 2
        nbx = (blocks_x - cx + 1) // 2
        nby = (blocks_y - cy + 1) // 2
        for b in prange(nbx * nby):
            bx = cx + 2 * (b % nbx)
            by = cy + 2 * (b // nbx)
            for cj in range(by * BLOCK, min((by + 1) * BLOCK, cells[1])):
                for ci in range(bx * BLOCK, min((bx + 1) * BLOCK, cells[0])):
                    cell = ci + cells[0] * cj
                    for k in range(starts[cell], starts[cell + 1]):
                        p = order[k]
                        _, ix, fx, wx, gx = fused._axis(3, x[p, 0], lower[0], inv_h[0], cells[0])
                        _, iy, fy, wy, gy = fused._axis(3, x[p, 1], lower[1], inv_h[1], cells[1])
                        m = mass[p]
                        vol = volume[p]
                        sxx, sxy = vol * stress[p, 0, 0], vol * stress[p, 0, 1]
                        syx, syy = vol * stress[p, 1, 0], vol * stress[p, 1, 1]
                        mvx, mvy = m * v[p, 0], m * v[p, 1]
                        mc00, mc01, mc10, mc11 = m * C[p, 0, 0], m * C[p, 0, 1], m * C[p, 1, 0], m * C[p, 1, 1]
                        for j in range(3):
                            dy = (j - fy) * h[1]
                            row = (iy + j) * strides[1]
                            for i in range(3):
                                node = row + (ix + i) * strides[0]
                                w = wx[i] * wy[j]
                                dwx = gx[i] * wy[j]
                                dwy = wx[i] * gy[j]
                                dx = (i - fx) * h[0]
                                grid_mass[node] += w * m
                                grid_mom[node, 0] += w * (mvx + mc00 * dx + mc01 * dy)
                                grid_mom[node, 1] += w * (mvy + mc10 * dx + mc11 * dy)
                                grid_force[node, 0] -= sxx * dwx + sxy * dwy
                                grid_force[node, 1] -= syx * dwx + syy * dwy


def measure(cells: int, threads: int, repeats: int) -> dict:
    sim = ExplicitMPM(load_scene(mls_block_scene(2, cells, threads)))
    for _ in range(2):
        sim.advance(1e-5)          # some strain, some C
    p, g, f = sim.particles, sim.grid, sim.frame
    n = p.count
    order = np.empty(n, dtype=np.int64)
    starts = np.empty(int(np.prod(g.cells)) + 1, dtype=np.int64)
    C = p.extra["affine"]

    def copies():
        sim.phases.particles_to_grid(1e-5)   # (resets the grid first)

    def coloured():
        g.reset()
        bin_by_cell(p.x, f.lower, f.inv_h, f.cells, order, starts)
        coloured_p2g(p.x, p.v, C, p.mass, p.volume, p.stress, f.lower, f.h, f.inv_h, f.cells, f.strides,
                     order, starts, g.mass, g.momentum, g.force)

    results = {}
    grids = {}
    for name, run in (("copies", copies), ("coloured", coloured)):
        run()
        grids[name] = (g.mass.copy(), g.momentum.copy(), g.force.copy())
    reps = max(3, int(2e6 / n))
    for name in ("copies", "coloured"):
        results[name] = np.inf
    for _ in range(repeats):
        for name, run in (("copies", copies), ("coloured", coloured)):
            start = time.perf_counter()
            for _ in range(reps):
                run()
            results[name] = min(results[name], (time.perf_counter() - start) / reps / n * 1e9)
    agree = max(float(np.max(np.abs(a - b)) / np.max(np.abs(b))) for a, b in zip(grids["copies"], grids["coloured"]))
    return {"particles": n, "threads": threads, **results, "agreement": agree}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    sizes = [56] if args.quick else [112, 225]
    print("| particles | threads | per-thread copies (ns/particle) | coloured blocks incl. sort (ns/particle) "
          "| copies / coloured | grids agree to |")
    print("|---|---|---|---|---|---|")
    for cells in sizes:
        for threads in (1, 2):
            r = measure(cells, threads, 2 if args.quick else 5)
            print(f"| {r['particles']:,} | {threads} | {r['copies']:.1f} | {r['coloured']:.1f} | "
                  f"{r['copies'] / r['coloured']:.2f} | {r['agreement']:.1e} |")
    print(f"\nload average during the run: {' '.join(f'{x:.1f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
