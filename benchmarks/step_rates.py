"""Time per step of every example, on this tree and, side by side, on another commit.

    python benchmarks/step_rates.py                      # this tree: us per step of each example
    python benchmarks/step_rates.py --base 13114c6       # and the same on that commit, alternately
    python benchmarks/step_rates.py --base HEAD~3 --examples two_disks taylor_bar_3d --repeats 5
    python benchmarks/step_rates.py --base main --blocks --examples   # the blocks of throughput.py only

Each measurement is its own process (a warm numba cache; the compile is not timed):
the example's scene at one thread (or --threads), 10 steps to warm up, then the best
of five runs of --steps steps. With --base the commit is checked out in a temporary
git worktree and the two trees are measured alternately, --repeats times each, so a
load that comes and goes hits both; the table gives the median of each tree's
repeats, the ratio base/this (above 1: this tree is faster) and the spread of the
repeats (max/min - 1, the noise of this machine at that moment).
"""
from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent

# Runs inside the tree being measured; works on commits before and after runner.make_simulation.
MEASURE = r"""
import json, sys, time
sys.path.insert(0, ".")
try:
    from solver.scene_checks import load_scene
except ImportError:   # commits before the checks left the schema
    from solver.scene import load_scene
try:
    from solver.runner import make_simulation
except ImportError:
    from solver.stepper import ExplicitMPM
    from solver.tlmpm import TotalLagrangianMPM
    def make_simulation(s):
        return (TotalLagrangianMPM if s.method.formulation == "tlmpm" else ExplicitMPM)(s)
scene = json.load(open(sys.argv[1] if sys.argv[1].endswith(".json") else f"examples/{sys.argv[1]}.json"))
scene["parallel"] = {**scene.get("parallel", {}), "threads": int(sys.argv[2])}
loaded = load_scene(scene)
sim = make_simulation(loaded)
def dt():
    return loaded.time.dt or sim.stable_time_step(loaded.time.cfl)
for _ in range(10):
    sim.advance(dt())
steps, best = int(sys.argv[3]), float("inf")
for _ in range(5):
    start = time.perf_counter()
    for _ in range(steps):
        sim.advance(dt())
    best = min(best, (time.perf_counter() - start) / steps)
print(json.dumps(best))
"""


def measure(tree: Path, example: str, threads: int, steps: int) -> float:
    done = subprocess.run([sys.executable, "-c", MEASURE, example, str(threads), str(steps)], cwd=tree,
                          capture_output=True, text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def steps_for(example: str) -> int:
    """Fewer steps for the large 3D examples and the blocks, so each measurement takes seconds."""
    return 10 if example in ("hypervelocity_lead", "taylor_bar_3d", "taylor_bar_3d_tlmpm") or example.endswith(".json") \
        else 50


def write_blocks(folder: Path, names: list[str]) -> list[str]:
    """The scenes of benchmarks/throughput.py as JSON files (measured by path in every tree):
    its part-2 block (linear elastic, linear hats, MUSL, FLIP) and its side-by-side block
    (neo-Hookean, quadratic B-splines, USL, APIC and MLS), 2D 225^2 cells and 3D 32^3 cells,
    and the mpm88 fluid (MLS); `names` picks some (none: all of them)."""
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from throughput import block_scene, mls_block_scene, mpm88_scene
    scenes = {"mpm88": mpm88_scene(1)}
    for dim, cells in ((2, 225), (3, 32)):
        scenes[f"block_flip_{dim}d"] = block_scene(dim, cells)
        scenes[f"block_apic_{dim}d"] = mls_block_scene(dim, cells, 1)
        scenes[f"block_mls_{dim}d"] = mls_block_scene(dim, cells, 1, "mls")
    unknown = sorted(set(names) - set(scenes))
    if unknown:
        raise SystemExit(f"--blocks: no scene {', '.join(unknown)} (there are {', '.join(scenes)})")
    paths = []
    for name, scene in scenes.items():
        if names and name not in names:
            continue
        path = folder / f"{name}.json"
        path.write_text(json.dumps(scene))
        paths.append(str(path))
    return paths


def compare(trees: dict[str, Path], examples: list[str], threads: int, repeats: int) -> list[dict]:
    rows = []
    for example in examples:
        times = {name: [] for name in trees}
        for _ in range(repeats):
            for name, tree in trees.items():
                times[name].append(measure(tree, example, threads, steps_for(example)))
        row = {"example": example, **{f"{n}_us": 1e6 * statistics.median(t) for n, t in times.items()},
               **{f"{n}_spread": max(t) / min(t) - 1.0 for n, t in times.items()}}
        if "base" in trees:
            row["ratio"] = row["base_us"] / row["this_us"]
        rows.append(row)
        print(" ".join(f"{k}={v:.3g}" if isinstance(v, float) else f"{k}={v}" for k, v in row.items()), flush=True)
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--base", help="a commit to measure side by side with this tree")
    parser.add_argument("--examples", nargs="*", default=sorted(p.stem for p in (ROOT / "examples").glob("*.json")))
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--json", type=Path, help="also write the rows as JSON")
    parser.add_argument("--blocks", nargs="*", metavar="NAME",
                        help="also the block scenes of benchmarks/throughput.py (names: those only, e.g. "
                             "block_flip_2d block_apic_3d; a base before MLS has no mpm88 nor block_mls_*)")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as scratch:
        trees = {"this": ROOT}
        blocks = write_blocks(Path(scratch), args.blocks) if args.blocks is not None else []
        if args.base:
            base = Path(scratch) / "base"
            subprocess.run(["git", "worktree", "add", "--detach", str(base), args.base], cwd=ROOT, check=True,
                           capture_output=True)
            trees["base"] = base
        common = [e for e in args.examples if all((tree / "examples" / f"{e}.json").exists() for tree in trees.values())]
        skipped = sorted(set(args.examples) - set(common))
        if skipped:
            print(f"not in both trees, skipped: {', '.join(skipped)}", flush=True)
        try:
            rows = compare(trees, blocks + common, args.threads, args.repeats)
        finally:
            if args.base:
                subprocess.run(["git", "worktree", "remove", "--force", str(trees["base"])], cwd=ROOT, check=False)
    print("\n| example | this (us/step) | base (us/step) | base / this | spread this, base |")
    print("|---|---|---|---|---|")
    for r in rows:
        base = f"{r['base_us']:.1f} | {r['ratio']:.3f}" if "base_us" in r else "- | -"
        spread = f"{r['this_spread']:.0%}" + (f", {r['base_spread']:.0%}" if "base_spread" in r else "")
        print(f"| {Path(r['example']).stem} | {r['this_us']:.1f} | {base} | {spread} |")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
