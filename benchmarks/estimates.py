"""The run-time estimate of every example (`mpm validate`, solver/cost.py) against the measured time.

    python benchmarks/estimates.py                        # run every example, print estimate vs measured
    python benchmarks/estimates.py --examples two_disks dam_break_2d
    python benchmarks/estimates.py --save runs.json       # keep the measured runs ...
    python benchmarks/estimates.py --load runs.json       # ... and compare a changed model without running

Each example runs as `python -m solver run EXAMPLE --progress json` in its own process,
as `mpm run` does (start-up, loading the compiled kernels, frames and the preview
included), once with the numba cache warm (an untimed run of a few steps first compiles
what is missing). The table gives the estimated and measured wall time, their ratio
(estimate / measured: the target is between 0.5 and 2), the estimated and actual step
counts, and the threads the run used.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from solver import cost  # noqa: E402
from solver.examples import list_examples, load_example  # noqa: E402
from solver.scene_checks import load_scene  # noqa: E402
from solver.summary import summarize, time_step  # noqa: E402


def run_once(scene: dict, steps: int | None = None) -> dict:
    """Run a scene as `mpm run` does; the 'done' line plus the wall time seen from outside."""
    if steps is not None:   # a few steps only (the warm-up that compiles what is missing)
        scene = {**scene, "time": {**scene["time"], "end": steps * time_step(load_scene(scene))}}
    with tempfile.TemporaryDirectory(prefix="mpm-estimate-") as tmp:
        path = Path(tmp) / "scene.json"
        path.write_text(json.dumps(scene))
        started = time.perf_counter()
        done = subprocess.run([sys.executable, "-m", "solver", "run", str(path), "-o", str(Path(tmp) / "out"),
                               "--progress", "json"], cwd=ROOT, capture_output=True, text=True)
        wall = time.perf_counter() - started
    lines = [json.loads(line) for line in done.stdout.splitlines() if line.startswith("{")]
    final = next((line for line in reversed(lines) if line.get("event") == "done"), None)
    if final is None:
        raise RuntimeError(f"the run failed: {done.stderr[-2000:]}")
    return {**final, "outside_seconds": wall}


def measure(names: list[str]) -> dict[str, dict]:
    runs = {}
    for name in names:
        scene = load_example(name)
        run_once(scene, steps=3)
        runs[name] = run_once(scene)
        print(f"measured {name}: {runs[name]['outside_seconds']:.2f} s, {runs[name]['steps']} steps",
              file=sys.stderr, flush=True)
    return runs


def table(runs: dict[str, dict]) -> list[dict]:
    rows = []
    for name, measured in runs.items():
        scene = load_scene(load_example(name))
        summary = summarize(scene)
        wall = measured["outside_seconds"]
        rows.append({"example": name, "estimate_s": summary.estimated_run_seconds, "measured_s": wall,
                     "ratio": summary.estimated_run_seconds / wall, "estimated_steps": summary.estimated_steps,
                     "steps": measured["steps"], "threads": cost.planned_threads(scene, summary.particles)})
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--examples", nargs="*", help="example names (default: all)")
    parser.add_argument("--save", help="write the measured runs to this JSON file")
    parser.add_argument("--load", help="read measured runs from this JSON file instead of running")
    args = parser.parse_args()
    names = args.examples or [e["name"] for e in list_examples()]
    if args.load:
        runs = {k: v for k, v in json.loads(Path(args.load).read_text()).items() if k in names}
    else:
        runs = measure(names)
    if args.save:
        Path(args.save).write_text(json.dumps(runs, indent=1))
    rows = table(runs)
    print(f"{'example':<26}{'estimate s':>11}{'measured s':>11}{'ratio':>7}{'est. steps':>11}{'steps':>8}{'thr':>4}")
    for r in rows:
        print(f"{r['example']:<26}{r['estimate_s']:>11.2f}{r['measured_s']:>11.2f}{r['ratio']:>7.2f}"
              f"{r['estimated_steps']:>11}{r['steps']:>8}{r['threads']:>4}")
    within = sum(0.5 <= r["ratio"] <= 2.0 for r in rows)
    print(f"{within} of {len(rows)} within a factor 2 (model: {cost.load_model().source})")
    return 0 if within == len(rows) else 1


if __name__ == "__main__":
    sys.exit(main())
