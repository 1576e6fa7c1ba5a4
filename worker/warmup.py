"""Compile the solver's kernels before the first job, so that it starts at once.

The kernels are compiled with numba's on-disk cache; running a tiny scene in a
child process (like a job) fills that cache for the common kernel variants.
"""
from __future__ import annotations

import json
import logging
import subprocess
import tempfile
import time
from pathlib import Path

from worker.runner import solver_command

log = logging.getLogger("mpm.worker")


def _tiny_scene(dimension: int, model: str) -> dict:
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
    }


# The kernel variants of the built-in examples and of the usual scenes.
WARMUP = ((1, "linear_elastic"), (2, "linear_elastic"), (2, "neo_hookean"),
          (3, "linear_elastic"), (3, "neo_hookean"))


def warm_up(timeout: float = 600.0) -> None:
    """Run each tiny scene once; a failure is logged, never fatal (jobs then compile)."""
    with tempfile.TemporaryDirectory(prefix="mpm-warmup-") as tmp:
        for dimension, model in WARMUP:
            name = f"{dimension}d_{model}"
            scene = Path(tmp) / f"{name}.json"
            scene.write_text(json.dumps(_tiny_scene(dimension, model)))
            started = time.monotonic()
            extra = {"dimension": dimension, "model": model}
            try:
                done = subprocess.run(solver_command(scene, Path(tmp) / name, progress="none"),
                                      capture_output=True, text=True, timeout=timeout)
            except subprocess.TimeoutExpired:
                log.warning("warm-up timed out", extra=extra)
                continue
            extra["seconds"] = round(time.monotonic() - started, 2)
            if done.returncode == 0:
                log.info("warm-up done", extra=extra)
            else:
                log.warning("warm-up failed", extra={**extra, "stderr": done.stderr[-2000:]})
