"""The elastic-block MLS-MPM step of benchmarks/reference_mls.py in NVIDIA Warp, on its CPU device.

    python mls_warp.py BLOCK.npz STEPS            -> one JSON line: particle-steps per second
    python mls_warp.py BLOCK.npz STEPS phases     -> also each kernel's best ns per particle

Run by benchmarks/throughput.py in its own process. Warp runs CPU kernels on one
thread. Same arithmetic as the numba reference: quadratic B-splines, the stress
folded into the APIC affine momentum, neo-Hookean Kirchhoff stress, float64.
"""
import json
import sys
import time
from typing import Any

import numpy as np
import warp as wp

from timing import report_rate

f64 = wp.float64


@wp.func
def bspline(f: wp.vec3d):
    """Row j: the weights of node j along each axis (the fractional positions f, in cells)."""
    a = wp.vec3d(f64(1.5), f64(1.5), f64(1.5)) - f
    b = f - wp.vec3d(f64(1.0), f64(1.0), f64(1.0))
    c = f - wp.vec3d(f64(0.5), f64(0.5), f64(0.5))
    return wp.mat33d(f64(0.5) * a[0] * a[0], f64(0.5) * a[1] * a[1], f64(0.5) * a[2] * a[2],
                     f64(0.75) - b[0] * b[0], f64(0.75) - b[1] * b[1], f64(0.75) - b[2] * b[2],
                     f64(0.5) * c[0] * c[0], f64(0.5) * c[1] * c[1], f64(0.5) * c[2] * c[2])


@wp.func
def stencil_2d(x: wp.vec2d, inv_dx: wp.float64):
    """A particle at x: the first of its 3 x 3 nodes (bx, by), its offset from that node in cells
    (fx, fy) and its weights (`bspline`'s rows)."""
    X = x * inv_dx
    bx = int(X[0] - f64(0.5))
    by = int(X[1] - f64(0.5))
    fx = X[0] - f64(bx)
    fy = X[1] - f64(by)
    return bx, by, fx, fy, bspline(wp.vec3d(fx, fy, f64(1.0)))


@wp.func
def stencil_3d(x: wp.vec3d, inv_dx: wp.float64):
    """`stencil_2d` in 3D: the first of the 3 x 3 x 3 nodes, the offset from it, the weights."""
    X = x * inv_dx
    bx = int(X[0] - f64(0.5))
    by = int(X[1] - f64(0.5))
    bz = int(X[2] - f64(0.5))
    fx = X[0] - f64(bx)
    fy = X[1] - f64(by)
    fz = X[2] - f64(bz)
    return bx, by, bz, fx, fy, fz, bspline(wp.vec3d(fx, fy, fz))


@wp.func
def kirchhoff_affine(Fp: Any, Cp: Any, eye: Any, m: wp.float64, vol: wp.float64, dt: wp.float64,
                     inv_dx: wp.float64, lam: wp.float64, mu: wp.float64):
    """The affine momentum that P2G scatters: m C_p with the neo-Hookean Kirchhoff stress
    tau = mu (F F^T - I) + lam ln J I folded in (MLS), in 2D or 3D (`eye` the identity)."""
    tau = mu * (Fp * wp.transpose(Fp) - eye) + lam * wp.log(wp.determinant(Fp)) * eye
    return (-dt * vol * f64(4.0) * inv_dx * inv_dx) * tau + m * Cp


@wp.func
def update_particle(x: Any, v: Any, C: Any, p: int, new_v: Any, new_C: Any, dt: wp.float64):
    """The end of G2P for particle p: v_p and C_p from the grid, x_p advected."""
    v[p] = new_v
    C[p] = new_C
    x[p] = x[p] + dt * new_v


@wp.func
def scatter_2d(x: wp.vec2d, m: wp.float64, v: wp.vec2d, affine: wp.mat22d, inv_dx: wp.float64,
               grid_m: wp.array2d(dtype=wp.float64), grid_v: wp.array2d(dtype=wp.vec2d)):
    """2D P2G of one particle: its mass m and affine momentum w (m v + affine (x_I - x)) into its 3 x 3 nodes."""
    bx, by, fx, fy, W = stencil_2d(x, inv_dx)
    dx = f64(1.0) / inv_dx
    mv = m * v
    for i in range(3):
        for j in range(3):
            w = W[i, 0] * W[j, 1]
            dpos = wp.vec2d((f64(i) - fx) * dx, (f64(j) - fy) * dx)
            wp.atomic_add(grid_v, bx + wp.int32(i), by + wp.int32(j), w * (mv + affine * dpos))
            wp.atomic_add(grid_m, bx + wp.int32(i), by + wp.int32(j), w * m)


@wp.func
def gather_2d(x: wp.array(dtype=wp.vec2d), v: wp.array(dtype=wp.vec2d), C: wp.array(dtype=wp.mat22d),
              grid_v: wp.array2d(dtype=wp.vec2d), dt: wp.float64, inv_dx: wp.float64, p: int):
    """2D G2P of particle p: v_p and C_p from the grid's velocities, x_p moved; returns C_p."""
    bx, by, fx, fy, W = stencil_2d(x[p], inv_dx)
    new_v = wp.vec2d()
    new_C = wp.mat22d()
    for i in range(3):
        for j in range(3):
            w = W[i, 0] * W[j, 1]
            g = grid_v[bx + wp.int32(i), by + wp.int32(j)]
            new_v = new_v + w * g
            new_C = new_C + (f64(4.0) * inv_dx * w) * wp.outer(g, wp.vec2d(f64(i) - fx, f64(j) - fy))
    update_particle(x, v, C, p, new_v, new_C, dt)
    return new_C


@wp.kernel
def p2g_2d(x: wp.array(dtype=wp.vec2d), v: wp.array(dtype=wp.vec2d), C: wp.array(dtype=wp.mat22d),
           F: wp.array(dtype=wp.mat22d), mass: wp.array(dtype=wp.float64), vol: wp.array(dtype=wp.float64),
           grid_m: wp.array2d(dtype=wp.float64), grid_v: wp.array2d(dtype=wp.vec2d),
           dt: wp.float64, inv_dx: wp.float64, lam: wp.float64, mu: wp.float64):
    p = wp.tid()
    affine = kirchhoff_affine(F[p], C[p], wp.identity(n=2, dtype=wp.float64), mass[p], vol[p], dt, inv_dx, lam, mu)
    scatter_2d(x[p], mass[p], v[p], affine, inv_dx, grid_m, grid_v)


@wp.kernel
def grid_2d(grid_m: wp.array2d(dtype=wp.float64), grid_v: wp.array2d(dtype=wp.vec2d)):
    i, j = wp.tid()
    if grid_m[i, j] > f64(0.0):
        grid_v[i, j] = grid_v[i, j] / grid_m[i, j]


@wp.kernel
def g2p_2d(x: wp.array(dtype=wp.vec2d), v: wp.array(dtype=wp.vec2d), C: wp.array(dtype=wp.mat22d),
           F: wp.array(dtype=wp.mat22d), grid_v: wp.array2d(dtype=wp.vec2d), dt: wp.float64, inv_dx: wp.float64):
    p = wp.tid()
    new_C = gather_2d(x, v, C, grid_v, dt, inv_dx, p)
    F[p] = (wp.identity(n=2, dtype=wp.float64) + dt * new_C) * F[p]


@wp.kernel
def p2g_3d(x: wp.array(dtype=wp.vec3d), v: wp.array(dtype=wp.vec3d), C: wp.array(dtype=wp.mat33d),
           F: wp.array(dtype=wp.mat33d), mass: wp.array(dtype=wp.float64), vol: wp.array(dtype=wp.float64),
           grid_m: wp.array3d(dtype=wp.float64), grid_v: wp.array3d(dtype=wp.vec3d),
           dt: wp.float64, inv_dx: wp.float64, lam: wp.float64, mu: wp.float64):
    p = wp.tid()
    bx, by, bz, fx, fy, fz, W = stencil_3d(x[p], inv_dx)
    affine = kirchhoff_affine(F[p], C[p], wp.identity(n=3, dtype=wp.float64), mass[p], vol[p], dt, inv_dx, lam, mu)
    dx = f64(1.0) / inv_dx
    mv = mass[p] * v[p]
    for i in range(3):
        for j in range(3):
            for k in range(3):
                w = W[i, 0] * W[j, 1] * W[k, 2]
                dpos = wp.vec3d((f64(i) - fx) * dx, (f64(j) - fy) * dx, (f64(k) - fz) * dx)
                wp.atomic_add(grid_v, bx + wp.int32(i), by + wp.int32(j), bz + wp.int32(k), w * (mv + affine * dpos))
                wp.atomic_add(grid_m, bx + wp.int32(i), by + wp.int32(j), bz + wp.int32(k), w * mass[p])


@wp.kernel
def grid_3d(grid_m: wp.array3d(dtype=wp.float64), grid_v: wp.array3d(dtype=wp.vec3d)):
    i, j, k = wp.tid()
    if grid_m[i, j, k] > f64(0.0):
        grid_v[i, j, k] = grid_v[i, j, k] / grid_m[i, j, k]


@wp.kernel
def g2p_3d(x: wp.array(dtype=wp.vec3d), v: wp.array(dtype=wp.vec3d), C: wp.array(dtype=wp.mat33d),
           F: wp.array(dtype=wp.mat33d), grid_v: wp.array3d(dtype=wp.vec3d), dt: wp.float64, inv_dx: wp.float64):
    p = wp.tid()
    bx, by, bz, fx, fy, fz, W = stencil_3d(x[p], inv_dx)
    new_v = wp.vec3d()
    new_C = wp.mat33d()
    for i in range(3):
        for j in range(3):
            for k in range(3):
                w = W[i, 0] * W[j, 1] * W[k, 2]
                g = grid_v[bx + wp.int32(i), by + wp.int32(j), bz + wp.int32(k)]
                new_v = new_v + w * g
                new_C = new_C + (f64(4.0) * inv_dx * w) * wp.outer(g, wp.vec3d(f64(i) - fx, f64(j) - fy, f64(k) - fz))
    update_particle(x, v, C, p, new_v, new_C, dt)
    F[p] = (wp.identity(n=3, dtype=wp.float64) + dt * new_C) * F[p]


def main(path: str, steps: int, phases: bool = False) -> None:
    wp.config.quiet = True
    wp.init()
    data = np.load(path)
    x0 = data["x"]
    n, dim = x0.shape
    cells = int(data["cells"])
    vec, mat = (wp.vec2d, wp.mat22d) if dim == 2 else (wp.vec3d, wp.mat33d)
    device = "cpu"
    x = wp.array(x0, dtype=vec, device=device)
    v = wp.array(data["v"], dtype=vec, device=device)
    C = wp.zeros(n, dtype=mat, device=device)
    F = wp.array(np.tile(np.eye(dim), (n, 1, 1)), dtype=mat, device=device)
    mass = wp.array(data["mass"], dtype=wp.float64, device=device)
    vol = wp.array(data["volume"], dtype=wp.float64, device=device)
    shape = (cells + 1,) * dim
    grid_m = wp.zeros(shape, dtype=wp.float64, device=device)
    grid_v = wp.zeros(shape, dtype=vec, device=device)
    p2g, grid, g2p = (p2g_2d, grid_2d, g2p_2d) if dim == 2 else (p2g_3d, grid_3d, g2p_3d)
    dt, inv_dx = f64(float(data["dt"])), f64(float(cells))
    lam, mu = f64(float(data["lam"])), f64(float(data["mu"]))

    def step():
        grid_m.zero_()
        grid_v.zero_()
        wp.launch(p2g, dim=n, inputs=[x, v, C, F, mass, vol, grid_m, grid_v, dt, inv_dx, lam, mu], device=device)
        wp.launch(grid, dim=shape, inputs=[grid_m, grid_v], device=device)
        wp.launch(g2p, dim=n, inputs=[x, v, C, F, grid_v, dt, inv_dx], device=device)

    report_rate(step, wp.synchronize, n, steps, x.numpy)
    if phases:
        _report_phases(n, {
            "zero + p2g": lambda: (grid_m.zero_(), grid_v.zero_(), wp.launch(
                p2g, dim=n, inputs=[x, v, C, F, mass, vol, grid_m, grid_v, dt, inv_dx, lam, mu], device=device)),
            "grid": lambda: wp.launch(grid, dim=shape, inputs=[grid_m, grid_v], device=device),
            "g2p": lambda: wp.launch(g2p, dim=n, inputs=[x, v, C, F, grid_v, dt, inv_dx], device=device)})


def _report_phases(n: int, phases: dict, repeats: int = 10) -> None:
    """Each kernel's best time over `repeats` steps (taken in the step's order), ns per particle."""
    best = {name: float("inf") for name in phases}
    for _ in range(repeats):
        for name, launch in phases.items():
            start = time.perf_counter()
            launch()
            wp.synchronize()
            best[name] = min(best[name], time.perf_counter() - start)
    print(json.dumps({"ns_per_particle": {name: t / n * 1e9 for name, t in best.items()}}))


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), len(sys.argv) > 3 and sys.argv[3] == "phases")
