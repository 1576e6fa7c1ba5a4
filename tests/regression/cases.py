"""The regression cases: every example, and a matrix of methods on two small scenes.

Each case is a scene, a step count and options: the thread count (results are
the same bits at the same thread count), and `general` to force the general
(stored-stencil) kernels on a scene the fused kernels would take.
"""
from __future__ import annotations

import copy
import itertools
import json
from dataclasses import dataclass, field
from pathlib import Path

from solver.mesh import inline_files

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
STEPS = 20
SMOOTH = ("quadratic_bspline", "cubic_bspline")   # the shape functions transfer "mls" takes
HEAVY = {"hypervelocity_lead": 8, "taylor_bar_3d": 10, "taylor_bar_3d_tlmpm": 10,   # 19k-37k particles in 3D
         "cold_spray_3d_quarter": 5}                                                # 77k


@dataclass
class Case:
    scene: dict
    steps: int = STEPS
    threads: int = 1
    general: bool = False
    slow: bool = False          # left out of the default run (`-m slow` runs it): `_slow_3d`
    notes: list[str] = field(default_factory=list)


def _example(name: str) -> dict:
    """The example's document, mesh files inlined (a case runs from the document alone)."""
    return inline_files(json.loads((EXAMPLES / f"{name}.json").read_text()), EXAMPLES)


def _with(scene: dict, threads: int, **method) -> dict:
    out = copy.deepcopy(scene)
    out["method"] = {**out.get("method", {}), **method}
    out["parallel"] = {**out.get("parallel", {}), "threads": threads}
    return out


def _method_matrix(base: dict, prefix: str, shapes: list[str], formulations=("ulmpm", "tlmpm")) -> dict[str, Case]:
    cases = {}
    for formulation, scheme, shape, transfer in itertools.product(
            formulations, ("usl", "musl", "usf"), shapes, ("flip", "pic", "apic", "mls")):
        if (transfer == "apic" and shape == "linear") or (transfer == "mls" and shape not in SMOOTH):
            continue                                   # refused by validation
        if shape == "bernstein" and formulation != "tlmpm":
            continue
        scene = _with(base, 1, formulation=formulation, scheme=scheme, shape_function=shape, transfer=transfer,
                      flip_ratio=0.95)
        cases[f"{prefix}-{formulation}-{scheme}-{shape}-{transfer}"] = Case(scene)
    return cases


def cases() -> dict[str, Case]:
    out: dict[str, Case] = {}
    for path in sorted(EXAMPLES.glob("*.json")):
        scene = _example(path.stem)
        for threads in (1, 2):
            out[f"example-{path.stem}-t{threads}"] = Case(_with(scene, threads), HEAVY.get(path.stem, STEPS), threads)
    disks = _example("two_disks")
    disks["grid"] = {**disks["grid"], "lower": [-0.6, -0.6], "upper": [0.6, 0.6]}   # room for every support
    out.update(_method_matrix(disks, "disks", ["linear", "gimp", "cpgimp", "quadratic_bspline", "cubic_bspline",
                                               "bernstein"]))
    cube = _example("elastic_cube_3d")
    out.update(_method_matrix(cube, "cube", ["linear", "quadratic_bspline", "cubic_bspline"], ("ulmpm",)))
    # the general kernels on scenes the fused ones take, at one and two threads; the fused run
    # at one thread is the method matrix's ulmpm case (`duplicates`)
    for prefix, base, scheme, shape, transfer, threads in _fused_matrix(disks, cube):
        scene = _with(base, threads, scheme=scheme, shape_function=shape, transfer=transfer, flip_ratio=0.95)
        if threads > 1:
            out[f"{prefix}-fused-{scheme}-{shape}-{transfer}-t{threads}"] = Case(scene, threads=threads)
        out[f"{prefix}-general-{scheme}-{shape}-{transfer}-t{threads}"] = Case(scene, threads=threads, general=True)
    for name, case in out.items():
        case.slow = _slow_3d(name)
    return out


# The 3D cases that the default run keeps: each compiles a 3D kernel variant of its own (40-70 s
# on one core, most of a cold run's regression time), so CI keeps per scheme and shape function
# one transfer of the method matrix, and one fused and two general runs of the comparison
# between backends; `python3 scripts/dev.py test -m slow tests/regression` runs the others.
REPRESENTATIVE_3D = {"linear": "flip", "quadratic_bspline": "apic", "cubic_bspline": "mls"}
COMPARISON_3D = {"cube-fused-musl-quadratic_bspline-mls-t2", "cube-general-usl-linear-flip-t1",
                 "cube-general-musl-quadratic_bspline-apic-t2"}


def _slow_3d(name: str) -> bool:
    if name.startswith("cube-ulmpm-"):
        _, _, _, shape, transfer = name.split("-")
        return REPRESENTATIVE_3D[shape] != transfer
    return name.startswith(("cube-fused-", "cube-general-")) and name not in COMPARISON_3D


def _fused_matrix(disks: dict | None = None, cube: dict | None = None):
    """(prefix, scene, scheme, shape, transfer, threads) of the scenes both backends take."""
    for (prefix, base), scheme, shape, transfer, threads in itertools.product(
            (("disks", disks), ("cube", cube)), ("usl", "musl"), ("linear", "quadratic_bspline"),
            ("flip", "pic", "apic", "mls"), (1, 2)):
        if not ((transfer == "apic" and shape == "linear") or (transfer == "mls" and shape not in SMOOTH)):
            yield prefix, base, scheme, shape, transfer, threads


def duplicates() -> dict[str, str]:
    """Recorded cases that another case runs scene for scene, by the other's name: the fused run
    at one thread (the baseline keeps it; tests/regression/test_regression.py holds its
    stored result to the other's instead of running it again)."""
    return {f"{prefix}-fused-{scheme}-{shape}-{transfer}-t1": f"{prefix}-ulmpm-{scheme}-{shape}-{transfer}"
            for prefix, _, scheme, shape, transfer, threads in _fused_matrix() if threads == 1}
