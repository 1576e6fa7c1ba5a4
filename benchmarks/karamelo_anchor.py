"""The seed anchor of issue 9: Karamelo's own 3D Taylor bar, run whole, on 1 and 2 processes.

    python benchmarks/karamelo_anchor.py            # the full 80 us on 2 processes (slabs balanced
                                                    # by particles, then by work), and on 1
    python benchmarks/karamelo_anchor.py --quick    # the first 10 us

Karamelo (C++/MPI) runs its 3D Taylor bar example (about 74k particles, OFHC
copper, Johnson-Cook with Mie-Grueneisen, linear ULMPM) at about 0.6 M
particle-steps/s per rank on this machine: about half an hour for the 80 us of
impact on 2 ranks. The goal here is >= 3 M particle-steps/s per process, the 80 us
in under 5 minutes on 2 processes.

The scene is examples/taylor_bar_3d.json made whole (the full cylinder instead
of a quarter, cell 0.5 mm: 73,696 particles) and run the way users run it,
`mpm run -n K` with one thread per process, adaptive dt (cfl 0.5). The wall time
is the runner's own, from the first step to the last write; particle-steps/s per
process is particles x steps / wall / K. The final length of the bar is printed
as a check that the run did the physics (experiment: 16.2 mm).

The energy series is written every step by default (the scene's `output.energies`);
Karamelo's input writes its log every N_log = 10 steps: `--energies 10` runs the bar
that way (the energies and the finiteness checks every 10 steps).
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from solver.results import read_frame  # noqa: E402

CELL = 0.0005
HALF_WIDTH = 0.00912   # grid half-width in x and z: room for the mushroom (13.5 mm across)


def anchor_scene(end: float, energies: int | None = None) -> dict:
    scene = json.loads((ROOT / "examples" / "taylor_bar_3d.json").read_text())
    bar = scene["bodies"][0]
    cylinder = bar["geometry"]["parts"][0]
    bar["geometry"] = cylinder                       # the whole bar, not its quarter
    scene["name"] = "Taylor bar 190 m/s, OFHC copper, whole 3D bar (Karamelo's example)"
    scene["grid"] = {"lower": [-HALF_WIDTH, 0.0, -HALF_WIDTH], "upper": [HALF_WIDTH, 0.0258, HALF_WIDTH],
                     "cell_size": CELL}
    scene["boundary_conditions"] = [{"type": "wall", "face": "y-", "mode": "slip"}]
    scene["time"]["end"] = end
    scene["output"] = {"frames": 2, "fields": ["position"]}
    if energies is not None:   # else every step, the default
        scene["output"]["energies"] = energies
    return scene


def run(scene: dict, processes: int, balance: str = "particles") -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        scene = {**scene, "parallel": {"processes": processes, "threads": 1, "balance": balance}}
        path = Path(tmp) / "scene.json"
        path.write_text(json.dumps(scene))
        out = Path(tmp) / "out"
        done = subprocess.run([sys.executable, "-m", "solver", "run", str(path), "-o", str(out), "-n",
                               str(processes), "--progress", "json"], capture_output=True, text=True, check=True,
                              cwd=ROOT)
        event = json.loads(done.stdout.strip().splitlines()[-1])
        x = read_frame(out / "result.h5", -1)["fields"]["position"]
    height = float(np.max(x[:, 1]) - np.min(x[:, 1]))
    diameter = float(np.max(x[:, 0]) - np.min(x[:, 0]))       # the mushroom's, across x
    rate = event["particles"] * event["steps"] / event["wall_seconds"]
    return {"processes": processes, "balance": balance, "particles": event["particles"], "steps": event["steps"],
            "time": event["time"], "wall_seconds": event["wall_seconds"], "rate_per_process": rate / processes,
            "length_mm": 1e3 * height, "diameter_mm": 1e3 * diameter}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="the first 10 us only")
    parser.add_argument("--json", type=Path, help="also write the rows as JSON")
    parser.add_argument("--energies", type=int, help="the energy series every N steps (default: every step; "
                        "Karamelo's input logs every N_log = 10 steps)")
    args = parser.parse_args()
    scene = anchor_scene(1e-5 if args.quick else 8e-5, args.energies)
    rows = [run(scene, 2), run(scene, 2, "work"), run(scene, 1)]
    one = rows[-1]["wall_seconds"]
    print("| processes | balance | particles | steps | simulated (us) | wall (s) | speed-up | "
          "M particle-steps/s per process | final length (mm) | final diameter (mm) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['processes']} | {r['balance']} | {r['particles']:,} | {r['steps']:,} | {r['time'] * 1e6:.1f} | "
              f"{r['wall_seconds']:.1f} | {one / r['wall_seconds']:.2f} | {r['rate_per_process'] / 1e6:.2f} | "
              f"{r['length_mm']:.2f} | {r['diameter_mm']:.2f} |")
    print(f"\nload average during the run: {' '.join(f'{x:.1f}' for x in os.getloadavg())}")
    if args.json:
        args.json.write_text(json.dumps(rows, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
