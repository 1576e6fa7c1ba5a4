"""Peak memory of a run against `mpm validate`'s estimate, on the 3D Taylor bar made finer.

    python benchmarks/memory.py                          # 0.3 M, 1 M and 3 M particles
    python benchmarks/memory.py --particles 12.4e6       # MPM3DMP's largest Taylor bar model

Each size is examples/taylor_bar_3d.json with its cell size divided so the bar seeds about
that many particles (2 per cell and axis, as the example); the run ends after about `--steps`
steps (time.end: that many estimated time steps) with a frame at t = 0 and one at the end, every
field of the example in them, and its preview drawn. A first run of the example compiles the
kernels where they are not cached. Each run is a process of its own (solver.runner.run, as `mpm
run` calls it): its peak resident set
(VmHWM, /proc/<pid>/status) is read as it exits. The estimate is `mpm validate`'s
(solver/summary.py memory_bytes: the process's own baseline included). Figures are on this
machine's thread count (the per-thread copies of the grid count).
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from solver.examples import load_example  # noqa: E402
from solver.scene_checks import load_scene  # noqa: E402
from solver.summary import summarize, time_step  # noqa: E402

BASE = "taylor_bar_3d"
BASE_PARTICLES = 35_687   # the example's, at its cell size


def scaled_scene(particles: float, steps: int) -> dict:
    """The example with its cell size shrunk so it seeds about `particles` (particles ~ h^-3),
    ending after about `steps` steps (the estimated dt) with a frame there: written once every
    array has been stepped on (np.zeros's pages are resident only once written)."""
    scene = load_example(BASE)
    scene["grid"]["cell_size"] *= (BASE_PARTICLES / particles) ** (1 / 3)
    scene["time"]["end"] = steps * time_step(load_scene(scene))
    scene["output"]["frames"] = 2   # t = 0 and the end
    return scene


# The child: run the scene as `mpm run` does, then report the process's peak resident set.
_CHILD = """
import json, sys
from solver.runner import run
result = run(sys.argv[1], sys.argv[2])
status = dict(line.split(":", 1) for line in open("/proc/self/status") if ":" in line)
print(json.dumps({"peak": int(status["VmHWM"].split()[0]) * 1024, "steps": result.steps,
                  "particles": result.particles, "wall": result.wall_seconds}))
"""

def measure(scene: dict) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "scene.json"
        path.write_text(json.dumps(scene))
        env = dict(os.environ, MPM_PRECOMPILE="0")
        started = time.perf_counter()
        done = subprocess.run([sys.executable, "-c", _CHILD, str(path), str(Path(tmp) / "out")], cwd=ROOT, env=env,
                              capture_output=True, text=True, check=True)
        out = json.loads(done.stdout.strip().splitlines()[-1])
        out["process_wall"] = time.perf_counter() - started
        return out


def row(particles: float, steps: int) -> dict:
    scene = scaled_scene(particles, steps)
    summary = summarize(load_scene(scene))
    measured = measure(scene)
    return {"particles": summary.particles, "nodes": summary.grid_nodes, "estimate": summary.memory_bytes,
            "peak": measured["peak"], "steps": measured["steps"], "wall": measured["process_wall"]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--particles", type=float, nargs="+", default=[3e5, 1e6, 3e6])
    parser.add_argument("--steps", type=int, default=3)
    parser.add_argument("--json", help="write the rows here too")
    args = parser.parse_args()
    measure(scaled_scene(BASE_PARTICLES, 1))   # compiles the kernels when cold: no row measures the compiler
    rows = []
    print(f"{'particles':>11} {'nodes':>10} {'estimate MiB':>12} {'peak MiB':>9} {'B/particle':>10} "
          f"{'peak/est':>8} {'wall s':>7}", flush=True)
    for particles in args.particles:
        r = row(particles, args.steps)
        rows.append(r)
        print(f"{r['particles']:>11,} {r['nodes']:>10,} {r['estimate'] / 2**20:>12.1f} {r['peak'] / 2**20:>9.1f} "
              f"{r['peak'] / r['particles']:>10.0f} {r['peak'] / r['estimate']:>8.3f} {r['wall']:>7.1f}", flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main()
