"""Scenes for the live tests, made from the service's own `two_disks` example so they
follow whatever the scene schema of the day is."""
from __future__ import annotations

import copy
from typing import Any

EXAMPLE = "two_disks"


def quick(example: dict[str, Any], name: str = "sdk-quick", frames: int = 6) -> dict[str, Any]:
    """The two colliding disks (about 3500 steps, a couple of seconds) with a few frames."""
    scene = copy.deepcopy(example)
    scene["name"] = name
    scene["output"]["frames"] = frames
    return scene


def slower(example: dict[str, Any], name: str, factor: float, frames: int = 6) -> dict[str, Any]:
    """The same collision in ``factor`` times as many, smaller, steps (a longer end time
    would let the disks fly off the grid, which ends the run as unstable)."""
    scene = quick(example, name, frames)
    scene["time"]["dt"] = example["time"]["dt"] / factor
    return scene


def long(example: dict[str, Any], name: str = "sdk-long") -> dict[str, Any]:
    """About 350 000 steps (minutes): a job to watch running and to cancel."""
    return slower(example, name, 100.0)


def unstable(example: dict[str, Any], name: str = "sdk-unstable") -> dict[str, Any]:
    """A time step 4x over the CFL limit: the run blows up within a few steps."""
    scene = quick(example, name)
    scene["time"]["dt"] = 0.2
    scene["time"]["end"] = 100.0
    scene["time"]["allow_unstable_dt"] = True   # validation refuses it otherwise (solver/stability.py)
    return scene


def invalid(example: dict[str, Any]) -> dict[str, Any]:
    """Two errors the validator must name by path."""
    scene = quick(example, "sdk-invalid")
    scene["bodies"][0]["geometry"]["radius"] = -0.2
    next(iter(scene["materials"].values()))["poisson_ratio"] = 0.7
    return scene
