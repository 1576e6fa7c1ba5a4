"""The elastic-block MLS-MPM step of benchmarks/reference_mls.py in Taichi, on its CPU backend.

    python mls_taichi.py BLOCK.npz THREADS STEPS     -> one JSON line: particle-steps per second

Run by benchmarks/throughput.py in its own process (Taichi brings its own LLVM and
thread pool). Same arithmetic as the numba reference: quadratic B-splines, the
stress folded into the APIC affine momentum, neo-Hookean Kirchhoff stress, float64.
"""

import sys

import numpy as np
import taichi as ti

from timing import report_rate


def main(path: str, threads: int, steps: int) -> None:
    data = np.load(path)
    ti.init(arch=ti.cpu, default_fp=ti.f64, cpu_max_num_threads=threads, log_level=ti.ERROR)
    x0 = data["x"]
    n, dim = x0.shape
    cells = int(data["cells"])
    lam, mu = float(data["lam"]), float(data["mu"])
    inv_dx, dx = float(cells), 1.0 / cells

    x = ti.Vector.field(dim, float, n)
    v = ti.Vector.field(dim, float, n)
    C = ti.Matrix.field(dim, dim, float, n)
    F = ti.Matrix.field(dim, dim, float, n)
    mass = ti.field(float, n)
    vol = ti.field(float, n)
    grid_v = ti.Vector.field(dim, float, (cells + 1,) * dim)
    grid_m = ti.field(float, (cells + 1,) * dim)

    @ti.kernel
    def step(dt: ti.f64):
        for I in ti.grouped(grid_m):
            grid_v[I] = ti.Vector.zero(float, dim)
            grid_m[I] = 0.0
        for p in x:
            Xp = x[p] * inv_dx
            base = int(Xp - 0.5)
            fx = Xp - base
            w = [0.5 * (1.5 - fx) ** 2, 0.75 - (fx - 1.0) ** 2, 0.5 * (fx - 0.5) ** 2]
            J = F[p].determinant()
            identity = ti.Matrix.identity(float, dim)
            tau = mu * (F[p] @ F[p].transpose() - identity) + lam * ti.log(J) * identity
            affine = -dt * vol[p] * 4.0 * inv_dx * inv_dx * tau + mass[p] * C[p]
            for offset in ti.static(ti.grouped(ti.ndrange(*((3,) * dim)))):
                dpos = (offset - fx) * dx
                weight = 1.0
                for d in ti.static(range(dim)):
                    weight *= w[offset[d]][d]
                grid_v[base + offset] += weight * (mass[p] * v[p] + affine @ dpos)
                grid_m[base + offset] += weight * mass[p]
        for I in ti.grouped(grid_m):
            if grid_m[I] > 0:
                grid_v[I] /= grid_m[I]
        for p in x:
            Xp = x[p] * inv_dx
            base = int(Xp - 0.5)
            fx = Xp - base
            w = [0.5 * (1.5 - fx) ** 2, 0.75 - (fx - 1.0) ** 2, 0.5 * (fx - 0.5) ** 2]
            new_v = ti.Vector.zero(float, dim)
            new_C = ti.Matrix.zero(float, dim, dim)
            for offset in ti.static(ti.grouped(ti.ndrange(*((3,) * dim)))):
                dpos = offset - fx
                weight = 1.0
                for d in ti.static(range(dim)):
                    weight *= w[offset[d]][d]
                g_v = grid_v[base + offset]
                new_v += weight * g_v
                new_C += 4.0 * inv_dx * weight * g_v.outer_product(dpos)
            v[p] = new_v
            C[p] = new_C
            x[p] += dt * new_v
            F[p] = (ti.Matrix.identity(float, dim) + dt * new_C) @ F[p]

    x.from_numpy(x0)
    v.from_numpy(data["v"])
    mass.from_numpy(data["mass"])
    vol.from_numpy(data["volume"])
    F.from_numpy(np.tile(np.eye(dim), (n, 1, 1)))
    C.from_numpy(np.zeros((n, dim, dim)))
    dt = float(data["dt"])
    report_rate(lambda: step(dt), ti.sync, n, steps, x.to_numpy)


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), int(sys.argv[3]))
