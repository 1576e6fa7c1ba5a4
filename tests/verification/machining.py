"""Orthogonal machining, Karamelo 4.4 (VERIFICATION_CASES E18): scene builder, the
Merchant estimate of the cutting force, and the measurements of a run.

The scene is examples/machining_2d.json: a 1 x 0.3 mm steel workpiece (Karamelo's Table 3:
Johnson-Cook flow stress with C = 0, Mie-Grueneisen, Johnson-Cook damage), TLMPM with one
particle per cell, fixed at its bottom and left faces, cut 0.15 mm deep by a rigid
frictionless wedge (a `tools` polygon, Hertz penalty) moving in -x at 50 m/s. Karamelo
gives the tool's angles only in its Fig. 14 and its input file is not among its published
examples: the example takes a 10 deg rake angle and a 6 deg clearance angle, usual values
for a carbide tool in steel.

Karamelo reports no number for this case (plots only). The reference here is Merchant's
orthogonal-cutting model (Merchant 1945) for a frictionless tool (friction angle
beta = 0): the shear angle that minimises the cutting work, phi = 45 deg + alpha / 2,
the shear strain of the chip gamma = cos(alpha) / (sin(phi) cos(phi - alpha)), and the
cutting force per unit width F_c = k t0 gamma, with k the shear flow stress on the shear
plane (F_c v = k gamma t0 v: the plastic work of the material that crosses it). The
material hardens from A to sigma(eps) across the plane (eps = gamma / sqrt 3, von Mises),
so k is bracketed by A / sqrt 3 (no hardening) and sigma(eps) / sqrt 3 (fully hardened);
the work-conjugate value is the mean flow stress, W(eps) / eps with
W = A eps + B eps^(n+1) / (n+1). The thrust force on a frictionless rake face is
F_t = -F_c tan(alpha) (the tool is pulled into the work), before any flank contact.
"""
from __future__ import annotations

import copy
import json
import math
from pathlib import Path

import numpy as np

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "machining_2d.json"
LENGTH, HEIGHT, DEPTH, SPEED = 1.0e-3, 0.3e-3, 0.15e-3, 50.0
RAKE_DEG = 10.0
TOOL = "cutter"


def example() -> dict:
    return json.loads(EXAMPLE.read_text())


def machining_scene(cells_x: int = 320, cells_y: int = 80, cut: float | None = None, frames: int | None = None,
                    energies: int | None = None) -> dict:
    """The example at cells_x x cells_y cells (one particle per cell), the tool moved `cut` (m)
    into the workpiece at the end (default: the example's end time)."""
    scene = copy.deepcopy(example())
    scene["grid"]["cell_size"] = [LENGTH / cells_x, HEIGHT / cells_y]
    if cut is not None:
        scene["time"]["end"] = cut / SPEED
    if frames is not None:
        scene["output"]["frames"] = frames
    if energies is not None:
        scene["output"]["energies"] = energies
    return scene


def rake_angle(scene: dict) -> float:
    """The tool's rake angle (rad) from its polygon: the rake face runs from the cutting edge,
    vertex 0, to vertex 3 (the vertices are rounded, so this is 10 deg to about 1e-7)."""
    vertices = scene["tools"][0]["geometry"]["vertices"]
    (x0, y0), (x3, y3) = vertices[0], vertices[3]
    return math.atan2(x3 - x0, y3 - y0)


def flow_stress(material: dict, eps: float) -> float:
    return material["A"] + material["B"] * eps ** material["n"]


def plastic_work(material: dict, eps: float) -> float:
    """int_0^eps sigma d eps of the Johnson-Cook flow stress (C = 0, no heating)."""
    n = material["n"]
    return material["A"] * eps + material["B"] * eps ** (n + 1) / (n + 1)


def merchant(material: dict, rake_deg: float = RAKE_DEG, depth: float = DEPTH) -> dict:
    """Merchant's frictionless estimate: shear angle, chip strain, and the cutting force per
    unit width with the shear flow stress at yield (low), the work-conjugate mean (mean)
    and fully hardened (high); the ratio F_t / F_c."""
    alpha = math.radians(rake_deg)
    phi = math.pi / 4 + alpha / 2
    gamma = math.cos(alpha) / (math.sin(phi) * math.cos(phi - alpha))
    eps = gamma / math.sqrt(3.0)
    root3 = math.sqrt(3.0)
    return {"phi_deg": math.degrees(phi), "gamma": gamma, "eps": eps,
            "low": material["A"] / root3 * depth * gamma,
            "mean": plastic_work(material, eps) / eps / root3 * depth * gamma,
            "high": flow_stress(material, eps) / root3 * depth * gamma,
            "thrust_ratio": -math.tan(alpha)}


def tool_travel(series: dict) -> np.ndarray:
    """How far the tool has moved into the workpiece at each series row (m)."""
    return SPEED * np.asarray(series["time"])


def cutting_forces(series: dict) -> tuple[np.ndarray, np.ndarray]:
    """F_c (along the cut, positive resisting the tool) and F_t (normal to the machined
    surface, positive pushing the tool up), per unit width (N/m): the material's force on the
    tool, reaction_cutter_<axis>, with the tool moving in -x."""
    return np.asarray(series[f"reaction_{TOOL}_x"]), np.asarray(series[f"reaction_{TOOL}_y"])


def plateau(series: dict, start: float) -> tuple[float, float]:
    """Mean and standard deviation of F_c over the rows where the tool has travelled past
    `start` (m)."""
    fc, _ = cutting_forces(series)
    late = tool_travel(series) > start
    return float(fc[late].mean()), float(fc[late].std())


def chip_rise(frame: dict, time: float) -> float:
    """How far the material ahead of the tool's cutting edge (within 2 depths of cut of it,
    above the cut line) has risen above the workpiece's original top surface (m)."""
    x = frame["fields"]["position"]
    edge = LENGTH - SPEED * time
    ahead = (x[:, 0] > edge - 2 * DEPTH) & (x[:, 0] < edge + DEPTH) & (x[:, 1] > HEIGHT - DEPTH)
    return float(x[ahead, 1].max() - HEIGHT)
