"""Cook's membrane, near-incompressible (docs/benchmarks.md, "F-bar").

    python benchmarks/cook.py            # MPM with and without F-bar, h = 4, 2, 1 (minutes)
    python benchmarks/cook.py --fem      # the finite element cross-check of the reference only

The scene, the measurement at the middle of the loaded edge (48, 52) and the published
reference are those of tests/verification/test_fbar_cook.py.
The cross-check (--fem): bilinear quadrilaterals (Q1) on an n x n mapped mesh of the
panel with the volumetric (lambda) term integrated at one point and the rest at 2 x 2
Gauss points (selective reduced integration, equivalent to the Q1-P0 mixed element,
which does not lock at poisson_ratio -> 1/2), plane strain, the traction as consistent
nodal forces, a dense solve; u_y at (48, 52) and at the corner C = (48, 60) for
n = 8 ... 64 and the Richardson extrapolation of the last three (observed order and limit),
with our data and with the published one's (Krysl: G = 0.375, lambda = 7500, load 1).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "verification"))

from test_fbar_cook import (E, MID_EDGE, NU, PUBLISHED, PUBLISHED_LOAD, PUBLISHED_SHEAR_MODULUS,  # noqa: E402
                            REFERENCE, TRACTION, run_cook)


def _mesh(n: int):
    """Nodes (n+1)^2 of the panel mapped from the unit square (xi along x, eta across)."""
    xi, eta = np.meshgrid(np.linspace(0, 1, n + 1), np.linspace(0, 1, n + 1), indexing="ij")
    bottom, top = 44 * xi, 44 + 16 * xi
    nodes = np.stack([48 * xi, bottom + eta * (top - bottom)], axis=-1).reshape(-1, 2)
    index = np.arange((n + 1) ** 2).reshape(n + 1, n + 1)
    elements = np.stack([index[:-1, :-1], index[1:, :-1], index[1:, 1:], index[:-1, 1:]], axis=-1).reshape(-1, 4)
    return nodes, elements, index


def _element_stiffness(corners, lam, mu):
    g = 1 / np.sqrt(3)
    K = np.zeros((8, 8))
    for points, weight, part in ((((-g, -g), (g, -g), (g, g), (-g, g)), 1.0, "shear"), (((0.0, 0.0),), 4.0, "volume")):
        for r, s in points:
            dN = 0.25 * np.array([[-(1 - s), (1 - s), (1 + s), -(1 + s)], [-(1 - r), -(1 + r), (1 + r), (1 - r)]])
            J = dN @ corners
            dx = np.linalg.solve(J, dN)                  # (2, 4) d N / d x
            B = np.zeros((3, 8))
            B[0, 0::2], B[1, 1::2] = dx[0], dx[1]
            B[2, 0::2], B[2, 1::2] = dx[1], dx[0]
            D = mu * np.diag([2.0, 2.0, 1.0]) if part == "shear" else lam * np.outer([1, 1, 0], [1, 1, 0])
            K += weight * np.linalg.det(J) * B.T @ D @ B
    return K


def fem_displacements(n: int, lam: float, mu: float, traction: float) -> tuple[float, float]:
    """u_y at (48, 52) and at C = (48, 60) of Q1 with selective reduced integration on an n x n
    mesh (n even: a node at the middle of the loaded edge)."""
    nodes, elements, index = _mesh(n)
    size = 2 * len(nodes)
    K = np.zeros((size, size))
    for element in elements:
        dofs = np.stack([2 * element, 2 * element + 1], axis=-1).ravel()
        K[np.ix_(dofs, dofs)] += _element_stiffness(nodes[element], lam, mu)
    f = np.zeros(size)
    edge = index[-1, :]                                  # x = 48, from y = 44 to 60
    for a, b in zip(edge[:-1], edge[1:]):
        half = 0.5 * traction * np.linalg.norm(nodes[b] - nodes[a])
        f[2 * a + 1] += half
        f[2 * b + 1] += half
    free = np.setdiff1d(np.arange(size), np.stack([2 * index[0, :], 2 * index[0, :] + 1]).ravel())
    u = np.zeros(size)
    u[free] = np.linalg.solve(K[np.ix_(free, free)], f[free])
    return float(u[2 * index[-1, n // 2] + 1]), float(u[2 * index[-1, -1] + 1])


def fem_table(sizes=(8, 16, 32, 64)) -> None:
    ours = (E * NU / ((1 + NU) * (1 - 2 * NU)), E / (2 * (1 + NU)), TRACTION)
    published = (7500.0, PUBLISHED_SHEAR_MODULUS, PUBLISHED_LOAD / 16)
    for name, data, reference in (("ours", ours, REFERENCE), ("published data", published, PUBLISHED)):
        values = np.array([fem_displacements(n, *data) for n in sizes])
        for n, (mid, corner) in zip(sizes, values):
            print(f"{name}: Q1-SRI n = {n:3d}: u_y(48, {MID_EDGE:g}) = {mid:.4f}, u_y(48, 60) = {corner:.4f}")
        for column, where in ((0, f"(48, {MID_EDGE:g})"), (1, "(48, 60)")):
            a, b, c = values[-3:, column]
            order = np.log2((b - a) / (c - b))
            limit = c + (c - b) / (2 ** order - 1)
            print(f"{name} at {where}: observed order {order:.2f}, Richardson limit {limit:.4f}"
                  + (f" (published, at (48, 52): {reference:.4f})" if column == 0 else ""))


def mpm_table(cells=(4.0, 2.0, 1.0)) -> None:
    print(f"| h | F-bar | u_y(48, {MID_EDGE:g}) | error vs {REFERENCE:.4f} | wall s |")
    print("|---|---|---|---|---|")
    for h in cells:
        for fbar in (False, True):
            start = time.perf_counter()
            u, _ = run_cook(h, fbar, Path("/tmp") / f"cook-{h}-{fbar}")
            print(f"| {h:g} | {'on' if fbar else 'off'} | {u:.3f} | {u / REFERENCE - 1:+.1%} | "
                  f"{time.perf_counter() - start:.0f} |", flush=True)


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--fem", action="store_true", help="only the finite element cross-check")
    args = parser.parse_args()
    fem_table()
    if not args.fem:
        mpm_table()
