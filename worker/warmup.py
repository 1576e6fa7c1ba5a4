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


def _tiny_scene(model: str) -> dict:
    return {
        "version": 1, "name": f"warm-up {model}", "dimension": 2,
        "grid": {"lower": [0.0, 0.0], "upper": [1.0, 1.0], "cell_size": 0.25},
        "materials": {"m": {"model": model, "density": 1000.0, "youngs_modulus": 1000.0,
                            "poisson_ratio": 0.3}},
        "bodies": [{"name": "b", "material": "m",
                    "geometry": {"type": "box", "lower": [0.25, 0.25], "upper": [0.75, 0.75]},
                    "particles_per_cell": 2, "initial_velocity": [0.1, 0.0]}],
        "time": {"end": 0.01, "dt": 0.001},
        "output": {"frames": 2},
    }


WARMUP_MODELS = ("linear_elastic", "neo_hookean")


def warm_up(timeout: float = 600.0) -> None:
    """Run each tiny scene once; a failure is logged, never fatal (jobs then compile)."""
    with tempfile.TemporaryDirectory(prefix="mpm-warmup-") as tmp:
        for model in WARMUP_MODELS:
            scene = Path(tmp) / f"{model}.json"
            scene.write_text(json.dumps(_tiny_scene(model)))
            started = time.monotonic()
            try:
                done = subprocess.run(solver_command(scene, Path(tmp) / model, progress="none"),
                                      capture_output=True, text=True, timeout=timeout)
            except subprocess.TimeoutExpired:
                log.warning("warm-up timed out", extra={"model": model})
                continue
            seconds = round(time.monotonic() - started, 2)
            if done.returncode == 0:
                log.info("warm-up done", extra={"model": model, "seconds": seconds})
            else:
                log.warning("warm-up failed", extra={"model": model, "seconds": seconds,
                                                     "stderr": done.stderr[-2000:]})
