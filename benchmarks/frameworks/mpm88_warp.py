"""Taichi's mpm88 (the weakly compressible fluid of benchmarks/reference_mls.py's `step_mpm88`)
in NVIDIA Warp, on its CPU device.

    python mpm88_warp.py BLOCK.npz STEPS     -> one JSON line: particle-steps per second

Run by benchmarks/throughput.py in its own process; Warp runs CPU kernels on one thread.
Same arithmetic as the numba reference and mpm88_taichi.py, float64.
"""
import sys

import numpy as np
import warp as wp

from mls_warp import gather_2d, scatter_2d
from timing import report_rate

f64 = wp.float64


@wp.kernel
def p2g(x: wp.array(dtype=wp.vec2d), v: wp.array(dtype=wp.vec2d), C: wp.array(dtype=wp.mat22d),
        J: wp.array(dtype=wp.float64), mass: wp.array(dtype=wp.float64), vol: wp.array(dtype=wp.float64),
        grid_m: wp.array2d(dtype=wp.float64), grid_v: wp.array2d(dtype=wp.vec2d),
        dt: wp.float64, inv_dx: wp.float64, bulk: wp.float64):
    p = wp.tid()
    stress = -dt * f64(4.0) * bulk * vol[p] * (J[p] - f64(1.0)) * inv_dx * inv_dx
    affine = wp.mat22d(stress, f64(0.0), f64(0.0), stress) + mass[p] * C[p]
    scatter_2d(x[p], mass[p], v[p], affine, inv_dx, grid_m, grid_v)


@wp.kernel
def grid(grid_m: wp.array2d(dtype=wp.float64), grid_v: wp.array2d(dtype=wp.vec2d), dt: wp.float64,
         gravity: wp.float64, bound: wp.int32, cells: wp.int32):
    i, j = wp.tid()
    g = grid_v[i, j]
    if grid_m[i, j] > f64(0.0):
        g = g / grid_m[i, j]
    g = wp.vec2d(g[0], g[1] - dt * gravity)
    if (i < bound and g[0] < f64(0.0)) or (i > cells - bound and g[0] > f64(0.0)):
        g = wp.vec2d(f64(0.0), g[1])
    if (j < bound and g[1] < f64(0.0)) or (j > cells - bound and g[1] > f64(0.0)):
        g = wp.vec2d(g[0], f64(0.0))
    grid_v[i, j] = g


@wp.kernel
def g2p(x: wp.array(dtype=wp.vec2d), v: wp.array(dtype=wp.vec2d), C: wp.array(dtype=wp.mat22d),
        J: wp.array(dtype=wp.float64), grid_v: wp.array2d(dtype=wp.vec2d), dt: wp.float64, inv_dx: wp.float64):
    p = wp.tid()
    new_C = gather_2d(x, v, C, grid_v, dt, inv_dx, p)
    J[p] = J[p] * (f64(1.0) + dt * (new_C[0, 0] + new_C[1, 1]))


def main(path: str, steps: int) -> None:
    wp.config.quiet = True
    wp.init()
    data = np.load(path)
    x0 = data["x"]
    n = x0.shape[0]
    cells = int(data["cells"])
    device = "cpu"
    x = wp.array(x0, dtype=wp.vec2d, device=device)
    v = wp.array(data["v"], dtype=wp.vec2d, device=device)
    C = wp.zeros(n, dtype=wp.mat22d, device=device)
    J = wp.array(np.ones(n), dtype=wp.float64, device=device)
    mass = wp.array(data["mass"], dtype=wp.float64, device=device)
    vol = wp.array(data["volume"], dtype=wp.float64, device=device)
    shape = (cells + 1, cells + 1)
    grid_m = wp.zeros(shape, dtype=wp.float64, device=device)
    grid_v = wp.zeros(shape, dtype=wp.vec2d, device=device)
    dt, inv_dx = f64(float(data["dt"])), f64(float(cells))
    bulk, gravity = f64(float(data["bulk"])), f64(float(data["gravity"]))
    bound = int(data["bound"])

    def step():
        grid_m.zero_()
        grid_v.zero_()
        wp.launch(p2g, dim=n, inputs=[x, v, C, J, mass, vol, grid_m, grid_v, dt, inv_dx, bulk], device=device)
        wp.launch(grid, dim=shape, inputs=[grid_m, grid_v, dt, gravity, bound, cells], device=device)
        wp.launch(g2p, dim=n, inputs=[x, v, C, J, grid_v, dt, inv_dx], device=device)

    report_rate(step, wp.synchronize, n, steps, x.numpy)


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]))
