"""Scaling of the process-level domain decomposition (issue 9) -> docs/benchmarks.md.

    python benchmarks/scaling.py            # the tables of docs/benchmarks.md
    python benchmarks/scaling.py --quick    # smaller problems, fewer steps
    python benchmarks/scaling.py --strong-only --repeats 3   # part 1 only, three times

1. Strong scaling: a 3D elastic block of about 200k particles, the same steps on
   1 and on 2 processes (mpiexec of the MPI wheel, as `mpm run -n K` starts them),
   wall time per step after warm-up; the speedup is the ratio of the two.
2. Weak scaling projected to 8, 64 and 512 processes: from the measured compute
   rate of one process and the measured halo traffic per step of the 2-process
   run (bytes each process sends in sum_ghosts/share_nodes, messages per step),
   with a stated network model (bandwidth, latency). Slabs keep their cross
   section, so the traffic per process does not grow with the process count.
3. Memory: bytes per particle of the solver's arrays (particles, stencil, grid)
   for a 2D and a 3D elastic scene.
4. A 1,000,000-particle 3D elastic scene: time per step and peak memory (RSS).

Each measurement runs in its own ranks (`python benchmarks/scaling.py --probe`);
rank 0 prints one JSON line.
"""
from __future__ import annotations

import argparse
import json
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from solver.parallel import launch  # noqa: E402

# Network model of the projection: an InfiniBand HDR-class cluster.
BANDWIDTH = 12.5e9        # bytes/s per process, one direction
LATENCY = 2e-6            # s per message
REDUCTIONS_PER_STEP = 4   # allreduce/bcast per step (time step, failures, report decision, migration count)
EXCHANGES_PER_STEP = 4    # MUSL: sum_ghosts twice, share_nodes twice


def block_scene(dim: int, cells: int, length: float = 1.0) -> dict:
    """An elastic block, 2 particles per cell per axis, moving and straining; the grid `length` long in x."""
    h = 0.3 / cells
    upper = [length] + [0.3] * (dim - 1)
    return {
        "name": f"scaling-{dim}d", "dimension": dim,
        "method": {"scheme": "musl", "transfer": "flip", "flip_ratio": 0.99},
        "grid": {"lower": [0.0] * dim, "upper": upper, "cell_size": h},
        "materials": {"m": {"model": "linear_elastic", "density": 1000.0, "youngs_modulus": 1e6,
                            "poisson_ratio": 0.3}},
        "bodies": [{"name": "block", "material": "m", "particles_per_cell": 2,
                    "geometry": {"type": "box", "lower": [2 * h] * dim, "upper": [u - 2 * h for u in upper]},
                    "initial_velocity": ["0.1 * sin(3 * x)"] + ["0.05"] * (dim - 1)}],
        "gravity": [0.0] * (dim - 1) + [-9.81],
        "time": {"end": 1.0, "dt": 1e-6},
        "output": {"frames": 2, "fields": ["position"]},
        "parallel": {"processes": 1, "rebalance_every": 100, "threads": 1},
    }


# -- the rank program --------------------------------------------------------------

# The domain's methods that talk to the other processes, timed in the probe: the halo
# exchanges, and the collectives (reductions, broadcasts, the migration's counts). Their
# time includes waiting for the slower process.
HALO = ("_exchange",)
COLLECTIVE = ("_reduce", "any", "root_says", "stop_if_failed", "migrate")


def time_calls(domain, names: tuple[str, ...]) -> list[float]:
    """Wrap the domain's methods `names` so that their seconds add up in the returned one-element list."""
    spent = [0.0]

    def timed(method):
        def call(*args, **kwargs):
            start = time.perf_counter()
            try:
                return method(*args, **kwargs)
            finally:
                spent[0] += time.perf_counter() - start
        return call

    for name in names:
        setattr(domain, name, timed(getattr(domain, name)))
    return spent


def probe(scene_path: str, steps: int, warmup: int) -> None:
    from solver.scene_checks import load_scene
    from solver.stepper import ExplicitMPM

    scene = load_scene(Path(scene_path))
    sim = ExplicitMPM(scene)
    d = sim.domain
    comm = getattr(d, "comm", None)
    halo_seconds = time_calls(d, HALO) if comm is not None else [0.0]
    collective_seconds = time_calls(d, COLLECTIVE) if comm is not None else [0.0]
    for _ in range(warmup):
        sim.advance(scene.time.dt)
    if comm is not None:
        comm.Barrier()
    halo_seconds[0] = collective_seconds[0] = 0.0
    bytes_before = getattr(d, "halo_bytes", 0)
    started = time.perf_counter()
    for _ in range(steps):
        sim.advance(scene.time.dt)
    if comm is not None:
        comm.Barrier()
    wall = time.perf_counter() - started
    halo = (getattr(d, "halo_bytes", 0) - bytes_before) / steps
    arrays = sum(a.nbytes for a in sim.particles.arrays().values())
    s = sim.stencil   # None where the fused kernels step (they keep v_pic instead, for MUSL)
    stencil = s.idx.nbytes + s.w.nbytes + s.dw.nbytes if s is not None else sim.rate.nbytes
    g = sim.grid
    grid = sum(a.nbytes for a in (g.mass, g.momentum, g.force, g.v_old, g.v_new))
    messages = len(getattr(d, "_ghosts", [])) + len(getattr(d, "_lent", []))
    mine = {"particles": sim.particles.count, "halo_bytes_per_step": halo, "messages_per_exchange": messages,
            "halo_seconds_per_step": halo_seconds[0] / steps,
            "collective_seconds_per_step": collective_seconds[0] / steps,
            "particle_bytes": arrays, "stencil_bytes": stencil, "grid_bytes": grid, "grid_nodes": g.mass.size,
            "rss_bytes": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024}
    everyone = comm.gather(mine, root=0) if comm is not None else [mine]
    if d.is_root:
        print(json.dumps({"wall_per_step": wall / steps, "steps": steps, "ranks": everyone}), flush=True)


def measure(scene: dict, processes: int, steps: int, warmup: int = 3) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "scene.json"
        path.write_text(json.dumps(scene))
        command = launch.python(processes, str(Path(__file__).resolve()), "--probe", str(path),
                                str(steps), str(warmup))
        done = subprocess.run(command, capture_output=True, text=True, env=launch.environment(), check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


# -- the tables ----------------------------------------------------------------------


def strong_scaling(cells: int, steps: int) -> tuple[list[str], dict, dict]:
    """1 process, 2 processes (one thread each), and 1 process of 2 threads, the same steps."""
    scene = block_scene(3, cells)
    one = measure(scene, 1, steps)
    two = measure(scene, 2, steps)
    threaded = scene | {"parallel": {**scene["parallel"], "threads": 2}}
    two_threads = measure(threaded, 1, steps)
    n = one["ranks"][0]["particles"]
    rows = ["| processes x threads | particles per process | wall per step (s) | M particle-steps/s | speedup |",
            "|---|---|---|---|---|"]
    for label, m in (("1 x 1", one), ("2 x 1", two), ("1 x 2", two_threads)):
        per = " / ".join(f"{r['particles']:,}" for r in m["ranks"])
        rows.append(f"| {label} | {per} | {m['wall_per_step']:.4f} | {n / m['wall_per_step'] / 1e6:.2f} | "
                    f"{one['wall_per_step'] / m['wall_per_step']:.2f} |")
    rows.append("")
    rows.append("2 x 1, per process: time in the halo exchanges / in the collectives, per step: " + ", ".join(
        f"{1e3 * r['halo_seconds_per_step']:.1f} / {1e3 * r['collective_seconds_per_step']:.1f} ms"
        for r in two["ranks"]))
    return rows, one, two


def weak_projection(one: dict, two: dict) -> list[str]:
    """t(P) = compute + halo / bandwidth + messages x latency + reductions x log2(P) x latency."""
    compute = one["wall_per_step"]                        # one process's particles, measured
    interior = max(two["ranks"], key=lambda r: r["halo_bytes_per_step"])
    # a process inside the chain of slabs has two neighbours: twice an end slab's traffic
    halo = 2 * interior["halo_bytes_per_step"]
    messages = EXCHANGES_PER_STEP * 2                     # one message to each neighbour per exchange
    rows = ["| processes | particles | compute per step (s) | halo per process per step | communication per step (s) "
            "| projected efficiency |", "|---|---|---|---|---|---|"]
    for p in (8, 64, 512):
        comm = halo / BANDWIDTH + messages * LATENCY + REDUCTIONS_PER_STEP * np.log2(p) * 2 * LATENCY
        rows.append(f"| {p} | {p * one['ranks'][0]['particles']:,} | {compute:.4f} | {halo / 1e3:.0f} kB | "
                    f"{comm:.2e} | {compute / (compute + comm):.1%} |")
    return rows


def johnson_cook_block(cells: int) -> dict:
    """The 3D block made of the Taylor bar's copper (Johnson-Cook, Mie-Grueneisen): plastic state per particle."""
    scene = block_scene(3, cells)
    taylor = json.loads((ROOT / "examples" / "taylor_bar_3d.json").read_text())
    scene["materials"] = {"m": taylor["materials"]["copper"]}
    scene["time"] = {"end": 1e-6, "dt": 1e-9}
    return scene


def memory_rows(cells_2d: int, cells_3d: int) -> list[str]:
    rows = ["| scene | particles | particle arrays (B/particle) | stencil or v_pic (B/particle) | grid (B/particle) "
            "| total (B/particle) |", "|---|---|---|---|---|---|"]
    for label, scene in (("2D elastic block", block_scene(2, cells_2d)),
                         ("3D Johnson-Cook block", johnson_cook_block(cells_3d))):
        r = measure(scene, 1, 1, warmup=0)["ranks"][0]
        n = r["particles"]
        total = r["particle_bytes"] + r["stencil_bytes"] + r["grid_bytes"]
        rows.append(f"| {label} | {n:,} | {r['particle_bytes'] / n:.0f} | {r['stencil_bytes'] / n:.0f} "
                    f"| {r['grid_bytes'] / n:.0f} | {total / n:.0f} |")
    return rows


def million(cells: int, steps: int) -> list[str]:
    m = measure(block_scene(3, cells, length=1.2), 1, steps, warmup=1)
    r = m["ranks"][0]
    return [f"A 3D elastic block of {r['particles']:,} particles ({r['grid_nodes']:,} grid nodes), one process: "
            f"{m['wall_per_step']:.2f} s per step ({r['particles'] / m['wall_per_step'] / 1e6:.2f} M particle-steps/s), "
            f"peak resident memory {r['rss_bytes'] / 2**30:.2f} GiB."]


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--probe":
        probe(sys.argv[2], int(sys.argv[3]), int(sys.argv[4]))
        return
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="smaller problems, fewer steps")
    parser.add_argument("--strong-only", action="store_true", help="part 1 only")
    parser.add_argument("--repeats", type=int, default=1, help="part 1 this many times")
    args = parser.parse_args()
    # 3D strong scaling: 23 cells across 0.3 -> 77 x 23 x 23 cells, about 208k particles
    cells, steps = (12, 5) if args.quick else (23, 20)
    for _ in range(args.repeats):
        rows, one, two = strong_scaling(cells, steps)
        print("\n".join(rows), "", sep="\n", flush=True)
    if args.strong_only:
        return
    print("\n".join(weak_projection(one, two)), "", sep="\n")
    print("\n".join(memory_rows(60 if args.quick else 150, 12 if args.quick else 23)), "", sep="\n")
    # 35 cells across 0.3, 1.2 long: 140 x 35 x 35 cells, about 1.05 M particles
    print("\n".join(million(12 if args.quick else 35, 2 if args.quick else 5)), flush=True)
    print(f"\nload average during the run: {' '.join(f'{x:.1f}' for x in __import__('os').getloadavg())}")


if __name__ == "__main__":
    main()
