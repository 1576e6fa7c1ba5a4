"""Where two processes lose against one: each rank's seconds by part of the step, side by side.

    python benchmarks/rank_breakdown.py              # Karamelo's whole 3D Taylor bar to 40 us
    python benchmarks/rank_breakdown.py --us 10 -n 3

The scene is benchmarks/karamelo_anchor.py's (73,950 particles, Johnson-Cook, one thread a
process). It runs once on one process and once on K ranks (`mpiexec -n K`, as `mpm run -n K`
starts them), each process under cProfile, and the table gives each part's seconds: the
kernels (a part that K ranks share evenly takes 1/K of the one-process time on each), what the
decomposition adds (migration, halo exchange, collectives: mostly a rank waiting for a slower
one), the step loop as a whole and what follows it. cProfile's own cost is in every column
alike; the speed-up of the loop is the ratio of the "step loop" rows.
"""
from __future__ import annotations

import argparse
import json
import pstats
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))   # (benchmarks/, the script's folder, is on the path already)

from karamelo_anchor import anchor_scene  # noqa: E402

from solver.parallel import launch  # noqa: E402

# Each process profiles `mpm run` and writes its statistics as profile.<rank>.
_PROFILED = """
import cProfile, os, runpy, sys
rank = os.environ.get("PMI_RANK", "0")
sys.argv = ["solver"] + sys.argv[1:]
profile = cProfile.Profile()
try:
    profile.runcall(runpy.run_module, "solver", run_name="__main__", alter_sys=True)
except SystemExit:
    pass
finally:
    profile.dump_stats(os.path.join(os.environ["PROFILES"], f"profile.{rank}"))
"""
# (part, how it is found: a function's name and, where the name is not unique, its file; whether its
# time is its own ("own"), includes what it calls ("all"), or is that of the run method that _run calls
# (runner.py's _TimeLoop.run, not the module's run: "loop"))
PARTS = [
    ("material update", "_update", "materials/kernels", "own"),
    ("material energy", "_energy", "materials/kernels", "own"),
    ("G2P kernels", "g2p", "fused", "own"),
    ("P2G kernels", "p2g", "fused", "own"),
    ("migration (its count's sum and its all-to-all included)", "migrate", "parallel/mpi.py", "all"),
    ("halo exchange", "_exchange", "parallel/mpi.py", "own"),
    ("other collectives (mostly waiting)", ("stop_if_failed", "_reduce", "root_says", "any", "allgather"),
     "parallel/mpi.py", "own"),
    ("step loop", "run", "solver/runner.py", "loop"),
    ("after the loop: waiting for rank 0", "all_ranks_done", "parallel/__init__.py", "all"),
]


def profile_runs(scene: dict, processes: int, folder: Path) -> list[pstats.Stats]:
    """Run the scene on `processes` ranks (1: a plain process), each profiled; their statistics."""
    scene = {**scene, "parallel": {"processes": processes, "threads": 1}}
    path = folder / f"scene{processes}.json"
    path.write_text(json.dumps(scene))
    profiles = folder / f"k{processes}"
    profiles.mkdir()
    program = folder / "profiled.py"
    program.write_text(_PROFILED)
    args = [str(program), "run", str(path), "-o", str(folder / f"out{processes}"), "--progress", "none"]
    command = launch.python(processes, *args) if processes > 1 else [sys.executable, *args]
    subprocess.run(command, check=True, capture_output=True, env={**launch.environment(), "PROFILES": str(profiles)})
    return [pstats.Stats(str(profiles / f"profile.{rank}")) for rank in range(processes)]


def seconds(stats: pstats.Stats, names, where: str, kind: str) -> float:
    """The seconds of the functions `names` defined in a file whose path contains `where`."""
    names = (names,) if isinstance(names, str) else names
    total = 0.0
    for (file, _, name), (_, _, own, cumulative, callers) in stats.stats.items():
        if name not in names or where not in file:
            continue
        if kind == "loop" and not any(caller[2] == "_run" for caller in callers):
            continue
        total += own if kind == "own" else cumulative
    return total


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--us", type=float, default=40.0, help="simulated microseconds (default 40)")
    parser.add_argument("-n", "--processes", type=int, default=2, help="ranks to compare with one process")
    args = parser.parse_args()
    scene = anchor_scene(args.us * 1e-6)
    with tempfile.TemporaryDirectory() as tmp:
        one = profile_runs(scene, 1, Path(tmp))[0]
        ranks = profile_runs(scene, args.processes, Path(tmp))
    print("| part | one process (s) | " + " | ".join(f"rank {r} (s)" for r in range(len(ranks))) + " |")
    print("|---|---|" + "---|" * len(ranks))
    rows = {part: [seconds(stats, names, where, kind) for stats in (one, *ranks)]
            for part, names, where, kind in PARTS}
    for part, row in rows.items():
        print(f"| {part} | " + " | ".join(f"{s:.2f}" for s in row) + " |")
    loop = rows["step loop"]
    print(f"\nstep loop speed-up on {len(ranks)} processes: {loop[0] / max(loop[1:]):.2f}x")
    return 0


if __name__ == "__main__":
    sys.exit(main())
