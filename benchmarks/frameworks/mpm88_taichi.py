"""Taichi's mpm88 (the weakly compressible fluid of benchmarks/reference_mls.py's `step_mpm88`)
on its CPU backend.

    python mpm88_taichi.py BLOCK.npz THREADS STEPS     -> one JSON line: particle-steps per second

Run by benchmarks/throughput.py in its own process. The kernel is Taichi's
python/taichi/examples/simulation/mpm88.py (quadratic B-splines, MLS-MPM, pressure
K (J - 1) in the affine momentum, J a scalar, gravity, walls 3 nodes thick) in float64,
on the particles the solver seeded (positions, masses, volumes from BLOCK.npz).
"""

import sys

import numpy as np
import taichi as ti

from timing import report_rate


def main(path: str, threads: int, steps: int) -> None:
    data = np.load(path)
    ti.init(arch=ti.cpu, default_fp=ti.f64, cpu_max_num_threads=threads, log_level=ti.ERROR)
    x0 = data["x"]
    n = x0.shape[0]
    cells = int(data["cells"])
    bulk, gravity, bound = float(data["bulk"]), float(data["gravity"]), int(data["bound"])
    inv_dx, dx = float(cells), 1.0 / cells

    x = ti.Vector.field(2, float, n)
    v = ti.Vector.field(2, float, n)
    C = ti.Matrix.field(2, 2, float, n)
    J = ti.field(float, n)
    mass = ti.field(float, n)
    vol = ti.field(float, n)
    grid_v = ti.Vector.field(2, float, (cells + 1, cells + 1))
    grid_m = ti.field(float, (cells + 1, cells + 1))

    @ti.kernel
    def step(dt: ti.f64):
        for i, j in grid_m:
            grid_v[i, j] = [0, 0]
            grid_m[i, j] = 0
        for p in x:
            Xp = x[p] * inv_dx
            base = int(Xp - 0.5)
            fx = Xp - base
            w = [0.5 * (1.5 - fx) ** 2, 0.75 - (fx - 1) ** 2, 0.5 * (fx - 0.5) ** 2]
            stress = -dt * 4 * bulk * vol[p] * (J[p] - 1) * inv_dx * inv_dx
            affine = ti.Matrix([[stress, 0], [0, stress]]) + mass[p] * C[p]
            for i, j in ti.static(ti.ndrange(3, 3)):
                offset = ti.Vector([i, j])
                dpos = (offset - fx) * dx
                weight = w[i].x * w[j].y
                grid_v[base + offset] += weight * (mass[p] * v[p] + affine @ dpos)
                grid_m[base + offset] += weight * mass[p]
        for i, j in grid_m:
            if grid_m[i, j] > 0:
                grid_v[i, j] /= grid_m[i, j]
            grid_v[i, j].y -= dt * gravity
            if i < bound and grid_v[i, j].x < 0:
                grid_v[i, j].x = 0
            if i > cells - bound and grid_v[i, j].x > 0:
                grid_v[i, j].x = 0
            if j < bound and grid_v[i, j].y < 0:
                grid_v[i, j].y = 0
            if j > cells - bound and grid_v[i, j].y > 0:
                grid_v[i, j].y = 0
        for p in x:
            Xp = x[p] * inv_dx
            base = int(Xp - 0.5)
            fx = Xp - base
            w = [0.5 * (1.5 - fx) ** 2, 0.75 - (fx - 1) ** 2, 0.5 * (fx - 0.5) ** 2]
            new_v = ti.Vector.zero(float, 2)
            new_C = ti.Matrix.zero(float, 2, 2)
            for i, j in ti.static(ti.ndrange(3, 3)):
                offset = ti.Vector([i, j])
                dpos = (offset - fx) * dx
                weight = w[i].x * w[j].y
                g_v = grid_v[base + offset]
                new_v += weight * g_v
                new_C += 4 * weight * g_v.outer_product(dpos) * inv_dx * inv_dx
            v[p] = new_v
            x[p] += dt * v[p]
            J[p] *= 1 + dt * new_C.trace()
            C[p] = new_C

    x.from_numpy(x0)
    v.from_numpy(data["v"])
    mass.from_numpy(data["mass"])
    vol.from_numpy(data["volume"])
    J.from_numpy(np.ones(n))
    C.from_numpy(np.zeros((n, 2, 2)))
    dt = float(data["dt"])
    report_rate(lambda: step(dt), ti.sync, n, steps, x.to_numpy)


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), int(sys.argv[3]))
