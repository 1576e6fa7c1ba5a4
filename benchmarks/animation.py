"""Time `mpm animate` (solver/animation.py): CPU and wall seconds of a GIF and an MP4 of
every frame of a result, repeated, with the file sizes (docs/benchmarks.md, "Animations").

    python benchmarks/animation.py                       # runs two_disks first, into a temp folder
    python benchmarks/animation.py out/run/result.h5 --repeat 3

CPU time is this process's (`time.process_time`): the drawing, which dominates; the MP4's
ffmpeg child is not counted. Wall time shows what a busy machine adds."""
from __future__ import annotations

import argparse
import tempfile
import time
from pathlib import Path

from solver import run
from solver.animation import render_animation
from solver.examples import load_example
from solver.results import list_frames


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("result", nargs="?", help="a result.h5 (default: run the two_disks example)")
    parser.add_argument("--repeat", type=int, default=2)
    args = parser.parse_args()
    folder = Path(tempfile.mkdtemp(prefix="mpm-animation-"))
    result = Path(args.result) if args.result else Path(run(load_example("two_disks"), folder / "run").result_path)
    frames = len(list_frames(result))
    print(f"{result}: {frames} frames")
    print(f"{'format':<6} {'CPU s':>7} {'wall s':>7} {'CPU s/frame':>12} {'bytes':>10}")
    for _ in range(args.repeat):
        for suffix in (".gif", ".mp4"):
            out = folder / f"animation{suffix}"
            cpu, wall = time.process_time(), time.perf_counter()
            render_animation(result, out)
            cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
            print(f"{suffix[1:]:<6} {cpu:7.2f} {wall:7.2f} {cpu / frames:12.3f} {out.stat().st_size:10d}")


if __name__ == "__main__":
    main()
