"""Scaling of the process-level domain decomposition (issue 9) -> docs/benchmarks.md.

    python benchmarks/scaling.py            # the tables of docs/benchmarks.md
    python benchmarks/scaling.py --quick    # smaller problems, fewer steps
    python benchmarks/scaling.py --strong-only --repeats 3   # part 1 only, three times

1. Strong scaling: a 3D elastic block of about 200k particles, the same steps on
   1 and on 2 processes (mpiexec of the MPI wheel, as `mpm run -n K` starts them),
   wall time per step after warm-up; the speedup is the ratio of the two.
2. Weak scaling projected to 2-1,024 processes: from the measured compute rate of
   one process and the measured halo traffic of the 2-process run (bytes each
   process sends in sum_ghosts/share_nodes for each node of the cut plane, halo
   exchanges and collectives per step), with a stated network model (bandwidth,
   latency); for slabs of a bar that grows along the cut (the traffic per process
   stays), and for a cube cut into slabs, pencils or blocks (solver/parallel/
   slabs.py's even cuts; the imbalance they leave counted).
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
from solver.parallel.slabs import even_cuts  # noqa: E402

# Network model of the projection: an InfiniBand HDR-class cluster.
BANDWIDTH = 12.5e9        # bytes/s per process, one direction
LATENCY = 2e-6            # s per message


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
    """Wrap the domain's methods `names` so that their seconds add up in the returned list's
    first element and their calls in its second."""
    spent = [0.0, 0]

    def timed(method):
        def call(*args, **kwargs):
            start = time.perf_counter()
            try:
                return method(*args, **kwargs)
            finally:
                spent[0] += time.perf_counter() - start
                spent[1] += 1
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
    halo_seconds = time_calls(d, HALO) if comm is not None else [0.0, 0]
    collective_seconds = time_calls(d, COLLECTIVE) if comm is not None else [0.0, 0]
    for _ in range(warmup):
        sim.advance(scene.time.dt)
    if comm is not None:
        comm.Barrier()
    halo_seconds[:] = collective_seconds[:] = [0.0, 0]
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
    grid = sum(a.nbytes for a in {id(a): a for a in (g.mass, g.momentum, g.force, g.v_old, g.v_new)}.values())
    messages = len(getattr(d, "_ghosts", [])) + len(getattr(d, "_lent", []))
    mine = {"particles": sim.particles.count, "halo_bytes_per_step": halo, "messages_per_exchange": messages,
            "halo_seconds_per_step": halo_seconds[0] / steps,
            "collective_seconds_per_step": collective_seconds[0] / steps,
            "exchanges_per_step": halo_seconds[1] / steps, "collectives_per_step": collective_seconds[1] / steps,
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


def _cube_factors(p: int, parts: int) -> list[int]:
    """`parts` factors of p, as near equal as they go (the process grid of pencils or blocks)."""
    if parts == 1:
        return [p]
    best = min((d for d in range(1, p + 1) if p % d == 0), key=lambda d: abs(d - round(p ** (1 / parts))))
    return sorted([best] + _cube_factors(p // best, parts - 1))


def weak_model(one: dict, two: dict, face_nodes: int) -> dict:
    """The single-rank costs the projection is built from, measured: compute seconds a
    particle-step (one process), halo bytes a step for each node of the cut plane (the busier
    process of two), exchanges and collectives a step; and, as a check of the imbalance model,
    two processes' busiest compute over their mean (wall less halo and collective seconds)."""
    ranks = two["ranks"]
    busy = [two["wall_per_step"] - r["halo_seconds_per_step"] - r["collective_seconds_per_step"] for r in ranks]
    return {"face_nodes": face_nodes, "particles": one["ranks"][0]["particles"],
            "seconds_per_particle_step": one["wall_per_step"] / one["ranks"][0]["particles"],
            "bytes_per_face_node": max(r["halo_bytes_per_step"] for r in ranks) / face_nodes,
            "exchanges": max(r["exchanges_per_step"] for r in ranks),
            "collectives": max(r["collectives_per_step"] for r in ranks),
            "measured_imbalance": max(busy) / (sum(busy) / len(busy))}


def projected(model: dict, p: int, decomposition: str) -> dict | None:
    """One process's step among p, each holding the measured process's particles, the whole
    problem a cube of 8 particles a cell (2 a cell and axis) cut into slabs, pencils or blocks;
    or, for "slabs of a bar", a bar that grows along the cut axis (its cross-section the
    measured one). An interior process has two neighbours along each cut axis (one where
    the axis is cut in two). Faces are exchanged one axis after the other, so edges and
    corners travel with them. Cuts fall on cell layers (solver/parallel/slabs.py even_cuts
    of the cube's whole cells), so the widest piece along each cut axis sets the imbalance,
    for particles of equal cost; a cut that leaves a piece without a layer cannot be made (None)."""
    n0 = model["particles"]
    beta = model["bytes_per_face_node"]
    if decomposition == "slabs of a bar":
        neighbours = 1 if p == 2 else 2
        width, halo = None, neighbours * beta * model["face_nodes"]
        imbalance = _widest_share(round(p * n0 / 8 / model["face_nodes"]), p)
    else:
        side = (p * n0 / 8) ** (1 / 3)                                   # the cube's cells a side
        counts = _cube_factors(p, {"slabs": 1, "pencils": 2, "blocks": 3}[decomposition])
        extents = [side / c for c in counts] + [side] * (3 - len(counts))   # the process's box, in cells
        width = min(extents[:len(counts)])
        shares = [_widest_share(round(side), c) for c in counts]
        if None in shares:
            return None
        sides = [0 if c == 1 else 1 if c == 2 else 2 for c in counts]   # neighbours along each cut axis
        neighbours = sum(sides)
        volume = extents[0] * extents[1] * extents[2]
        halo = sum(k * beta * volume / extents[a] for a, k in enumerate(sides))
        imbalance = float(np.prod(shares))
    messages = model["exchanges"] * neighbours
    compute = model["seconds_per_particle_step"] * n0
    comm = halo / BANDWIDTH + messages * LATENCY + model["collectives"] * np.log2(p) * 2 * LATENCY
    return {"width": width, "halo": halo, "messages": messages, "imbalance": imbalance, "comm": comm,
            "efficiency": compute / (compute * imbalance + comm)}


def _widest_share(layers: int, pieces: int) -> float | None:
    """The widest of `pieces` even cuts of `layers` cell layers over their mean; None where one has none."""
    widths = np.diff(even_cuts(layers, pieces))
    return None if widths.min() < 1 else float(widths.max() / widths.mean())


DECOMPOSITIONS = {"slabs of a bar": "slabs of a bar", "slabs": "slabs of a cube",
                  "pencils": "pencils (2D grid of processes)", "blocks": "blocks (3D, faces one axis after another)"}
PROCESS_COUNTS = (2, 8, 64, 512, 1024)


def weak_projection(one: dict, two: dict, face_nodes: int) -> list[str]:
    """t(P) = compute x imbalance + halo / bandwidth + messages x latency + collectives x 2 log2(P) x latency."""
    model = weak_model(one, two, face_nodes)
    rows = [f"Measured: {1e9 * model['seconds_per_particle_step']:.0f} ns a particle-step on one process "
            f"({model['particles']:,} particles); {model['bytes_per_face_node']:.0f} halo bytes a step for each node "
            f"of the cut plane; {model['exchanges']:.0f} halo exchanges and {model['collectives']:.0f} collectives a "
            f"step; the busier of two processes computed {model['measured_imbalance']:.3f} of their mean. "
            f"Network: {BANDWIDTH / 1e9:.1f} GB/s, {LATENCY * 1e6:.0f} us a message.", "",
            "Each cell: projected efficiency (halo a process sends a step, messages a step; imbalance; narrowest "
            "cut in cells).", "",
            "| decomposition | " + " | ".join(f"{p:,} processes" for p in PROCESS_COUNTS) + " |",
            "|---|" + "---|" * len(PROCESS_COUNTS)]
    for decomposition, label in DECOMPOSITIONS.items():
        cells = []
        for p in PROCESS_COUNTS:
            r = projected(model, p, decomposition)
            width = "" if r is None or r["width"] is None else f"; {r['width']:.1f}"
            cells.append("cannot be cut" if r is None else
                         f"{r['efficiency']:.1%} ({r['halo'] / 1e3:,.0f} kB, {r['messages']:.0f}; "
                         f"{r['imbalance']:.3f}{width})")
        rows.append(f"| {label} | " + " | ".join(cells) + " |")
    rows += ["", _where_slabs_stop(model)]
    return rows


def _where_slabs_stop(model: dict) -> str:
    """Where slabs of a cube stop scaling (under 90 %, then no cell layer left to a slab) and
    what blocks, the next decomposition, keep at the largest count."""
    slabs, p = {}, 2
    while (r := projected(model, p, "slabs")) is not None:
        slabs[p], p = r, p + 1
    uncuttable = p
    below = next((p for p, r in slabs.items() if r["efficiency"] < 0.9), None)
    largest = PROCESS_COUNTS[-1]
    blocks, pencils = projected(model, largest, "blocks"), projected(model, largest, "pencils")
    falls = f"fall under 90 % from {below} processes and" if below and below < uncuttable else "stay above 90 % but"
    return (f"Slabs of a cube {falls} cannot be cut past {uncuttable - 1} processes (a slab without a cell "
            f"layer); the next decomposition is blocks, a 3D process grid exchanging faces one axis after another: "
            f"{blocks['efficiency']:.1%} at {largest:,} (pencils {pencils['efficiency']:.1%}).")


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
    face_nodes = (cells + 1) ** 2   # the cut plane: x has the most cells (block_scene), y and z `cells` each
    print("\n".join(weak_projection(one, two, face_nodes)), "", sep="\n")
    print("\n".join(memory_rows(60 if args.quick else 150, 12 if args.quick else 23)), "", sep="\n")
    # 35 cells across 0.3, 1.2 long: 140 x 35 x 35 cells, about 1.05 M particles
    print("\n".join(million(12 if args.quick else 35, 2 if args.quick else 5)), flush=True)
    print(f"\nload average during the run: {' '.join(f'{x:.1f}' for x in __import__('os').getloadavg())}")


if __name__ == "__main__":
    main()
