"""The fused P2G and G2P kernels of this tree against those of another commit's template, in one
process, on the same arrays, taking turns (so a shared machine's load hits both alike).

    python benchmarks/fused_kernels_ab.py --base HEAD~1
    python benchmarks/fused_kernels_ab.py --base b2c6f06 --cases mpm88 mls3 --threads 1 2 --rounds 30

A case's scene is stepped a few times on this tree, then one P2G and one G2P call (MUSL: both
G2P calls, the remap and the kinematics pass) are caught with their arguments; both templates'
kernels then run on copies of those arguments, --rounds times each. The table gives the median
ns per particle of each, their ratio (above 1: this tree is faster) and the largest difference
of the arrays they wrote, relative to each array's largest entry ("bits" where they are equal).
Only a base whose kernels take this tree's arguments can be compared (solver/fused_template.py
`_p2g`, `_g2p` signatures).
"""
from __future__ import annotations

import argparse
import importlib.util
import inspect
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path[:0] = [str(ROOT), str(ROOT / "benchmarks")]

from throughput import DT, MLS_DT, MPM88_DT, block_scene, mls_block_scene, mpm88_scene  # noqa: E402
from solver.scene_checks import load_scene  # noqa: E402
from solver.fused import REMAP  # noqa: E402
from solver.stepper import ExplicitMPM  # noqa: E402

FLIP = {"scheme": "usl", "shape_function": "quadratic_bspline", "transfer": "flip", "flip_ratio": 0.99}
CASES = ("mpm88", "mls2", "mls3", "apic2", "apic3", "flip2", "flip3", "musl2", "musl3")


def case_scene(name: str, threads: int) -> tuple[dict, float]:
    """mpm88's fluid, throughput.py's neo-Hookean block (2D 225^2 cells, 3D 32^3) with MLS,
    APIC or FLIP (0.99), USL, or its part-2 block (musl: linear elastic, linear hats, MUSL, FLIP)."""
    if name == "mpm88":
        return mpm88_scene(threads), MPM88_DT
    if name.startswith("musl"):
        dim = int(name[-1])
        scene = block_scene(dim, 225 if dim == 2 else 32)
        scene["parallel"] = {"threads": threads}
        return scene, DT
    transfer, dim = name[:-1], int(name[-1])
    scene = mls_block_scene(dim, 225 if dim == 2 else 32, threads, "mls" if transfer == "mls" else "apic")
    if transfer == "flip":
        scene["method"] = dict(FLIP)
    return scene, MLS_DT


def base_template(rev: str, folder: Path):
    """The module solver/fused_template.py of commit `rev` (its helpers from this tree)."""
    text = subprocess.run(["git", "show", f"{rev}:solver/fused_template.py"], cwd=ROOT, capture_output=True,
                          text=True, check=True).stdout
    path = folder / "base_fused_template.py"
    path.write_text(text)
    spec = importlib.util.spec_from_file_location("base_fused_template", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def caught_calls(sim, dt: float) -> dict:
    """The arguments of one step's P2G and G2P calls (MUSL: "remap", the G2P call that maps the
    momentum back, and "g2p", the kinematics pass)."""
    kernels, calls = sim.phases._kernels, {}

    class Catch:
        def p2g(self, *args):
            calls["p2g"] = args
            return kernels.p2g(*args)

        def g2p(self, *args):
            calls["remap" if args[0][1].ndim - 1 == REMAP else "g2p"] = args
            return kernels.g2p(*args)

    sim.phases._kernels = Catch()
    sim.advance(dt)
    sim.phases._kernels = kernels
    return calls


_LOADED: dict = {}


def base_kernels(sim, template, folder: Path):
    """The base template's kernels for the scene's dimension and material lines (one module,
    and so one compile, per text in a run)."""
    from solver.step.fused import _material_lines
    model = sim.phases._stress_model
    lines = {"stress": _material_lines(sim, model, "stress_lines")}
    if "update" in inspect.signature(template.source).parameters:   # (a base before the G2P update has none)
        lines["update"] = _material_lines(sim, model, "stress_update_lines")
    text = template.source(sim.scene.dimension, **lines)
    if text not in _LOADED:
        path = folder / f"base_fused_{len(_LOADED)}.py"
        path.write_text(text)
        spec = importlib.util.spec_from_file_location(path.stem, path)
        _LOADED[text] = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(_LOADED[text])
    return _LOADED[text]


def _copies(args: tuple) -> tuple:
    return tuple(a.copy() if isinstance(a, np.ndarray) and a.size > 1000 else a for a in args)


def _largest_difference(a: tuple, b: tuple) -> float:
    worst = 0.0
    for x, y in zip(a, b):
        if isinstance(x, np.ndarray) and x.size > 1000 and x.dtype == np.float64:
            worst = max(worst, float(np.max(np.abs(x - y)) / max(float(np.max(np.abs(x))), 1e-300)))
    return worst


def compare(name: str, threads: int, rounds: int, template, folder: Path) -> dict:
    import numba
    numba.set_num_threads(threads)
    scene, dt = case_scene(name, threads)
    sim = ExplicitMPM(load_scene(scene))
    for _ in range(3):
        sim.advance(dt)
    calls = caught_calls(sim, dt)
    trees = {"base": base_kernels(sim, template, folder), "this": sim.phases._kernels}
    times = {(tree, kernel): [] for tree in trees for kernel in calls}
    written = {}
    for round_ in range(rounds + 2):   # (the first two warm up)
        for tree, module in trees.items():
            for kernel, args in calls.items():
                copies = _copies(args)
                start = time.perf_counter()
                getattr(module, "p2g" if kernel == "p2g" else "g2p")(*copies)
                if round_ >= 2:
                    times[tree, kernel].append(time.perf_counter() - start)
                written[tree, kernel] = copies
    n = sim.particles.count
    row = {"case": name, "threads": threads, "particles": n}
    for kernel in calls:
        base, this = (statistics.median(times[t, kernel]) / n * 1e9 for t in trees)
        row[kernel] = (base, this, base / this, _largest_difference(written["base", kernel], written["this", kernel]))
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--base", required=True, help="the commit whose solver/fused_template.py is the base")
    parser.add_argument("--cases", nargs="+", choices=CASES, default=list(CASES))
    parser.add_argument("--threads", nargs="+", type=int, default=[1, 2])
    parser.add_argument("--rounds", type=int, default=20)
    args = parser.parse_args()
    print("| case | threads" + "".join(f" | {k} base / this (ns) | ratio | written, rel. diff" for k in
                                     ("P2G", "G2P", "MUSL remap")) + " |\n|" + "---|" * 11)
    with tempfile.TemporaryDirectory() as tmp:
        template = base_template(args.base, Path(tmp))
        for threads in args.threads:
            for name in args.cases:
                row = compare(name, threads, args.rounds, template, Path(tmp))
                cells = []
                for kernel in ("p2g", "g2p", "remap"):
                    if kernel not in row:
                        cells += ["-"] * 3
                        continue
                    base, this, ratio, diff = row[kernel]
                    cells += [f"{base:.2f} / {this:.2f}", f"{ratio:.3f}", "bits" if diff == 0.0 else f"{diff:.1e}"]
                print(f"| {name} | {threads} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
