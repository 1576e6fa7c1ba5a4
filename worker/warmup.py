"""Compile the solver's kernels behind a ready worker, so that the first jobs find them compiled.

The kernels are kept in the versioned kernel cache (solver/kernel_cache.py); running a
tiny scene in a child process (like a job) fills it for the common kernel variants. A
variant already marked compiled in this version's cache (solver/cost.py) is skipped
without starting a process, so a restarted worker warms up in well under a second. The
worker takes jobs meanwhile (they compile what they need, and load what the warm-up
saved); `GET /v1/health` lists it under "warming" until it is done.

Each variant is compiled in the forms the worker's jobs will run (solver/jit.py): the serial
twins, which a job on one thread runs (a small scene), and where a job may take several of
the cores, the parallel forms.
"""
from __future__ import annotations

import json
import logging
import os
import subprocess
import tempfile
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Callable

from core.processes import killed_with_parent
from worker.runner import solver_command

log = logging.getLogger("mpm.worker")


def _tiny_scene(dimension: int, model: str, threads: int) -> dict:
    """A box of one material moving through a 4-cell grid, for a hundredth of a second."""
    return {
        "version": 1, "name": f"warm-up {dimension}D {model}", "dimension": dimension,
        "grid": {"lower": [0.0] * dimension, "upper": [1.0] * dimension, "cell_size": 0.25},
        "materials": {"m": {"model": model, "density": 1000.0, "youngs_modulus": 1000.0,
                            "poisson_ratio": 0.3}},
        "bodies": [{"name": "b", "material": "m",
                    "geometry": {"type": "box", "lower": [0.25] * dimension, "upper": [0.75] * dimension},
                    "particles_per_cell": 2, "initial_velocity": [0.1] + [0.0] * (dimension - 1)}],
        "time": {"end": 0.01, "dt": 0.001},
        "output": {"frames": 2},
        "parallel": {"threads": threads},
    }


# The kernel variants of the built-in examples and of the usual scenes.
WARMUP = ((1, "linear_elastic"), (2, "linear_elastic"), (2, "neo_hookean"),
          (3, "linear_elastic"), (3, "neo_hookean"))


def thread_counts(job_cores: int) -> tuple[int, ...]:
    """The thread counts that give the kernels' forms a worker's jobs run: one, and the job's
    share of the cores where that is more (any count above one runs the same parallel forms)."""
    return (1,) if job_cores <= 1 else (1, job_cores)


def pending(variants=WARMUP, threads: tuple[int, ...] = (1,)) -> list[tuple[int, str, int]]:
    """The (dimension, model, threads) not yet compiled into this version's kernel cache."""
    from solver import cost
    from solver.scene_checks import load_scene

    return [(dim, model, count) for dim, model in variants for count in threads
            if not cost.is_compiled(load_scene(_tiny_scene(dim, model, count)), count)]


def _compile(dimension: int, model: str, threads: int, folder: Path, timeout: float) -> None:
    name = f"{dimension}d_{model}_{threads}t"
    scene = folder / f"{name}.json"
    scene.write_text(json.dumps(_tiny_scene(dimension, model, threads)))
    started = time.monotonic()
    extra = {"dimension": dimension, "model": model, "threads": threads}
    try:
        # a worker killed while it warms up (kill -9, `mpm serve` stopped) leaves no compile running
        done = subprocess.run(solver_command(scene, folder / name, progress="none"),
                              capture_output=True, text=True, timeout=timeout, preexec_fn=killed_with_parent)
    except subprocess.TimeoutExpired:
        log.warning("warm-up timed out", extra=extra)
        return
    extra["seconds"] = round(time.monotonic() - started, 2)
    if done.returncode == 0:
        log.info("warm-up done", extra=extra)
    else:
        log.warning("warm-up failed", extra={**extra, "stderr": done.stderr[-2000:]})


def warm_up(timeout: float = 600.0, workers: int | None = None,
            warming: Callable[[bool], None] = lambda _: None, job_cores: int = 1) -> None:
    """Compile the pending variants for jobs of `job_cores` cores, one process per core; a failure
    is logged, never fatal (jobs then compile). `warming(True)` before and `warming(False)` after,
    for the health page."""
    todo = pending(threads=thread_counts(job_cores))
    if not todo:
        log.info("warm-up: every variant is in the kernel cache")
        return
    warming(True)
    try:
        with tempfile.TemporaryDirectory(prefix="mpm-warmup-") as tmp, \
                ThreadPoolExecutor(workers or min(len(todo), os.cpu_count() or 1)) as pool:
            for future in [pool.submit(_compile, *variant, Path(tmp), timeout) for variant in todo]:
                future.result()
    finally:
        warming(False)
