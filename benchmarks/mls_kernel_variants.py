"""Variants of the 2D MLS kernels that were measured (docs/benchmarks.md at 35cd95b
and be2413e): where the P2G's time goes, what numba's SLP vectorizer does to them, and the
vectorised G2P the solver keeps.

    python benchmarks/mls_kernel_variants.py [--repeats 11]
    python benchmarks/mls_kernel_variants.py --alone {2d,mpm88} {solver,numba}
    python benchmarks/mls_kernel_variants.py --save-block block.npz   # for frameworks/mls_warp.py ... phases

On the 2D neo-Hookean block of benchmarks/throughput.py (225 x 225 cells, 129,600 particles,
quadratic B-splines, MLS, USL), one thread, the state after three steps. Prints ns per particle,
the best and the median of the repeats, each variant timed in turn within a repeat.

Part 1, P2G: the folded MLS P2G written out as solver/fused_template.py emits it (the stress
formed from F_p, dt f_I in the momentum), on the same state:
  - `separate`:    m_I and (mv)_I in two arrays, as the solver keeps them;
  - `interleaved`: (m, mv_x, mv_y) of a node side by side in one (n, 3) array;
  - `no log`:      log J replaced by J - 1 (not a kernel: what the log costs);
  - `inline log`:  log J by fdlibm's reduction and polynomial for J in [1/sqrt 2, sqrt 2]
                   (libm's log outside), inlined; at most 1 ulp from libm's log.
Part 2, G2P: the solver's own generated G2P (USL, MLS), compiled twice from the same text,
without and with numba's SLP vectorizer (numba.config.SLP_VECTORIZE, off by default), and the
P2G likewise.
Part 3, G2P in two passes on flat views of the arrays, as LLVM's loop vectorizer would need
it across particles: a gather of v_p and C_p that only reads x_p, then x_p, F_p and V_p (the
same results to round-off). `--remarks` prints LLVM's loop-vectorizer remarks while they compile.
Part 4, the G2P's particle update put off into the next P2G: whole steps of the solver with its
generated scalar kernels (`p2g`, `g2p`), and with kernels whose G2P stops after v_p and C_p and whose P2G first moves
x_p and updates F_p and V_p (the same bits: checked after five steps, the update pending).
Part 5, the solver's two USL G2P kernels for MLS, from the same generated text: `g2p` (one
scalar pass, as parts 2-4 call it) and `g2p_mls` (the loop LLVM vectorises: solver/fused_template.py
`_g2p_mls`), with the number of AVX-512 gathers in each one's code, and whether the particles
come out the same bits.
Part 6, P2G: the solver's two folded MLS P2G kernels, `p2g` (scalar) and `p2g_mls` (its work per
particle vectorised in chunks, log J from solver/near_one_log.py: solver/fused_template.py
`_p2g_mls`), and whether the nodes come out the same bits.

--alone: one stepper's rate in a process of its own, timed as benchmarks/frameworks/timing.py
times Taichi and Warp (three untimed steps, the best of three runs of 15 steps), where
throughput.py times the solver's steppers and the numba reference taking turns in one process.
"""
from __future__ import annotations

import argparse
import math
import sys
import time
import types
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

import llvmlite.binding as llvm  # noqa: E402
import numba  # noqa: E402
from numba import njit  # noqa: E402

from solver import fused, fused_template  # noqa: E402
from solver.scene_checks import load_scene  # noqa: E402
from solver.step.fused import _material_lines  # noqa: E402
from solver.stepper import ExplicitMPM  # noqa: E402
from reference_mls import ReferenceMLS, ReferenceMPM88  # noqa: E402
from throughput import (MLS_DT, MPM88_BULK, MPM88_DT, MPM88_GRAVITY, mls_block_scene, mpm88_scene, rate,  # noqa: E402
                        save_mls_block)

LG = (6.666666666666735130e-01, 3.999999999940941908e-01, 2.857142874366239149e-01, 2.222219843214978396e-01,
      1.818357216161805012e-01, 1.531383769920937332e-01, 1.479819860511658591e-01)


@njit(inline="always", fastmath=False)
def inline_log(x):
    """fdlibm's log for x in (1/sqrt 2, sqrt 2), where no exponent is split off; libm outside."""
    if 0.7071067811865476 < x < 1.4142135623730951:
        f = x - 1.0
        s = f / (2.0 + f)
        z = s * s
        w = z * z
        r = z * (LG[0] + w * (LG[2] + w * (LG[4] + w * LG[6]))) + w * (LG[1] + w * (LG[3] + w * LG[5]))
        hfsq = 0.5 * f * f
        return f - (hfsq - s * (hfsq + r))
    return math.log(x)


P2G = '''
@njit(parallel=True, fastmath={{"contract"}})
def p2g(x, v, C, mass, volume, F, q0, q1, lower, inv_h, cells, h0, h1, stride1, offset, d_inv0, d_inv1, dt,
        grid_mass, grid_mom, bounds):
    for t in prange(1):
        for p in range(np.uint64(bounds[t]), np.uint64(bounds[t + 1])):
            f00, f01, f10, f11 = F[p, 0, 0], F[p, 0, 1], F[p, 1, 0], F[p, 1, 1]
            fj = f00 * f11 - f01 * f10
            nh_c = q0 * {log} / fj
            sig00 = q1 / fj * ((0.0 + f00 * f00 + f01 * f01) - 1.0) + nh_c
            sig01 = q1 / fj * ((0.0 + f00 * f10 + f01 * f11) - 0.0) + 0.0
            sig10 = q1 / fj * ((0.0 + f10 * f00 + f11 * f01) - 0.0) + 0.0
            sig11 = q1 / fj * ((0.0 + f10 * f10 + f11 * f11) - 1.0) + nh_c
            _, ix, fx, wx, _ = _axis(3, x[p, 0], lower[0], inv_h[0], cells[0])
            _, iy, fy, wy, _ = _axis(3, x[p, 1], lower[1], inv_h[1], cells[1])
            m = mass[p]
            mvx, mvy = m * v[p, 0], m * v[p, 1]
            vol = volume[p]
            s00, s01 = dt * (vol * sig00 * d_inv0), dt * (vol * sig01 * d_inv1)
            s10, s11 = dt * (vol * sig10 * d_inv0), dt * (vol * sig11 * d_inv1)
            mc00, mc01 = m * C[p, 0, 0] - s00, m * C[p, 0, 1] - s01
            mc10, mc11 = m * C[p, 1, 0] - s10, m * C[p, 1, 1] - s11
            for j in range(3):
                dy = (j - fy) * h1
                row = (iy + j) * stride1 - offset
                rx = mvx + mc01 * dy
                ry = mvy + mc11 * dy
                for i in range(3):
                    node = np.uint64(row + ix + i)
                    w = wx[i] * wy[j]
                    dx = (i - fx) * h0
                    px = rx + mc00 * dx
                    py = ry + mc10 * dx
{scatter}
'''
SEPARATE = """                    grid_mass[node] += w * m
                    grid_mom[node, 0] += w * px
                    grid_mom[node, 1] += w * py"""
INTERLEAVED = """                    grid_mom[node, 0] += w * m
                    grid_mom[node, 1] += w * px
                    grid_mom[node, 2] += w * py"""


def _module(name: str, text: str, slp: bool = False):
    """Compile `text` as a module (numba's cache off); `slp` turns numba's SLP vectorizer on
    for the compiles this module's first calls make (the pass builder reads it then)."""
    module = types.ModuleType(name)
    module.__dict__.update(np=np, njit=njit, prange=numba.prange, math=math, inline_log=inline_log)
    exec(compile(text.replace("cache=True", "cache=False"), f"<{name}>", "exec"), module.__dict__)
    module.slp = slp
    return module


def _timed(calls: dict, n: int, repeats: int, before=None) -> dict:
    times = {name: [] for name in calls}
    for _ in range(repeats):
        for name, call in calls.items():
            if before:
                before()
            start = time.perf_counter()
            call()
            times[name].append((time.perf_counter() - start) / n * 1e9)
    return times


def _print(title: str, times: dict) -> None:
    print(title)
    for name, t in times.items():
        print(f"  {name:<28} best {min(t):6.2f}   median {np.median(t):6.2f} ns/particle")


def _first_call(module, call):
    old = numba.config.SLP_VECTORIZE
    numba.config.SLP_VECTORIZE = int(module.slp)
    try:
        call()
    finally:
        numba.config.SLP_VECTORIZE = old


def part_p2g(sim, repeats: int) -> None:
    p, f, ph = sim.particles, sim.frame, sim.phases
    q0, q1 = ph._stress_parameters[:2]
    n_nodes = sim.grid.n_nodes
    grids = {"separate": (np.zeros(n_nodes), np.zeros((n_nodes, 2))), "interleaved": (np.zeros(1), np.zeros((n_nodes, 3))),
             "no log": (np.zeros(n_nodes), np.zeros((n_nodes, 2))), "inline log": (np.zeros(n_nodes), np.zeros((n_nodes, 2)))}
    texts = {"separate": ("math.log(fj)", SEPARATE), "interleaved": ("math.log(fj)", INTERLEAVED),
             "no log": ("(fj - 1.0)", SEPARATE), "inline log": ("inline_log(fj)", SEPARATE)}
    header = "from solver.fused import _axis\n"
    kernels = {name: _module("p2g_" + name.replace(" ", "_"), header + P2G.format(log=log, scatter=scatter))
               for name, (log, scatter) in texts.items()}
    args = (p.x, p.v, ph._affine_matrix, p.mass, p.volume, p.F, q0, q1, f.lower, f.inv_h, f.cells, f.h[0], f.h[1],
            f.strides[1], f.offset, ph._d_inv[0], ph._d_inv[1], MLS_DT)
    bounds = np.array([0, p.count])

    def call(name):
        mass, mom = grids[name]
        mass.fill(0.0)
        mom.fill(0.0)
        kernels[name].p2g(*args, mass, mom, bounds)
    calls = {name: (lambda name=name: call(name)) for name in kernels}
    for c in calls.values():
        c()
    sep_m, sep_p = grids["separate"]
    same = np.array_equal(sep_m, grids["interleaved"][1][:, 0]) and np.array_equal(sep_p, grids["interleaved"][1][:, 1:])
    log_moved = np.max(np.abs(grids["inline log"][1] - sep_p)) / np.max(np.abs(sep_p))
    _print("P2G, folded MLS, neo-Hookean stress formed in the pass", _timed(calls, p.count, repeats))
    print(f"  interleaved: the same bits as separate: {same}; inline log: the momentum moves by {log_moved:.1e} "
          "(relative to its largest)")
    j = np.random.default_rng(1).uniform(0.71, 1.41, 1_000_000)
    ulps = np.abs(_apply_inline_log(j) - np.log(j)) / np.spacing(np.log(j))
    print(f"  inline log on 1e6 values in (0.71, 1.41): at most {ulps.max():.0f} ulp from numpy's log, "
          f"{np.mean(ulps > 0):.1%} differ")


@njit
def _apply_inline_log(values):
    out = np.empty_like(values)
    for i in range(values.size):
        out[i] = inline_log(values[i])
    return out


def _generated_g2p(sim, module) -> None:
    """The USL G2P of a module of generated kernels on the sim's state, as FusedPhases calls it."""
    ph, p, g = sim.phases, sim.particles, sim.grid
    module.g2p(ph._g2p_variants[fused.USL, True, False], p.x, p.v, ph._affine_matrix, p.mass, p.stored("L"), p.F,
               p.volume, p.volume0, sim.rate, ph._frame, g.v_old, g.v_new, g.momentum, sim.flip_ratio, MLS_DT,
               ph._d_inv, sim.copies.momentum, p.stored("stress"), ph._stress_parameters, ph._bad)


def part_slp(sim, plain, repeats: int) -> None:
    """`plain`: the generated kernels compiled as numba does by default (shared with parts 3, 4)."""
    ph, p, g = sim.phases, sim.particles, sim.grid
    slp = _module("fused_slp", fused_template.source(2, stress=_lines(sim)), slp=True)
    restore = _restorer(sim)

    def g2p(module):
        _generated_g2p(sim, module)

    def p2g(module):
        c = sim.copies
        module.p2g(ph._p2g_variants[True, True], p.x, p.v, ph._affine_matrix, p.mass, p.volume, p.stored("stress"), p.F,
                   ph._affine_matrix, p.volume0, ph._stress_parameters, ph.acceleration, ph._frame, ph._d_inv, g.mass,
                   g.momentum, g.force, c.mass, c.momentum, c.force, ph._bad, MLS_DT)
    for module in (plain, slp):
        _first_call(module, lambda: (restore(), g2p(module), g.reset(), p2g(module)))
    restore()
    _print("G2P (USL, MLS), the solver's generated kernel", _timed(
        {"SLP off (numba's default)": lambda: g2p(plain), "SLP on": lambda: g2p(slp)}, p.count, repeats, restore))
    _print("P2G (folded MLS), the solver's generated kernel", _timed(
        {"SLP off (numba's default)": lambda: p2g(plain), "SLP on": lambda: p2g(slp)}, p.count, repeats, g.reset))
    restore()


TWO_PASSES = '''
@njit(parallel=True, fastmath={{"contract"}})
def gather(x, v, C, v_new, lower0, lower1, inv_h0, inv_h1, h0, h1, cells0, cells1, stride1, offset, d_inv0, d_inv1,
           bounds):
    for t in prange(1):
        for p in range(bounds[t], bounds[t + 1]):
            s0, s1 = (x[2 * p] - lower0) * inv_h0, (x[2 * p + 1] - lower1) * inv_h1
            ix, iy = min(max(np.int64(s0 - 0.5), 0), cells0 - 2), min(max(np.int64(s1 - 0.5), 0), cells1 - 2)
            fx, fy = s0 - ix, s1 - iy
            wx0, wx1, wx2 = 0.5 * ((1.5 - fx) * (1.5 - fx)), 0.75 - (fx - 1.0) * (fx - 1.0), 0.5 * ((fx - 0.5) * (fx - 0.5))
            wy0, wy1, wy2 = 0.5 * ((1.5 - fy) * (1.5 - fy)), 0.75 - (fy - 1.0) * (fy - 1.0), 0.5 * ((fy - 0.5) * (fy - 0.5))
            wdx0, wdx1, wdx2 = wx0 * ((0 - fx) * h0), wx1 * ((1 - fx) * h0), wx2 * ((2 - fx) * h0)
            base = iy * stride1 - offset + ix
            vpx = vpy = b00 = b01 = b10 = b11 = 0.0
{rows}
            v[2 * p], v[2 * p + 1] = vpx, vpy
            C[4 * p], C[4 * p + 1] = b00 * d_inv0, b01 * d_inv1
            C[4 * p + 2], C[4 * p + 3] = b10 * d_inv0, b11 * d_inv1


@njit(parallel=True, fastmath={{"contract"}})
def update(x, v, C, F, volume, volume0, dt, bounds, bad):
    for t in prange(1):
        nbad = 0
        for p in range(bounds[t], bounds[t + 1]):
            x[2 * p] += dt * v[2 * p]
            x[2 * p + 1] += dt * v[2 * p + 1]
            l00, l01, l10, l11 = C[4 * p], C[4 * p + 1], C[4 * p + 2], C[4 * p + 3]
            f00, f01, f10, f11 = F[4 * p], F[4 * p + 1], F[4 * p + 2], F[4 * p + 3]
            n00 = f00 + dt * l00 * f00 + dt * l01 * f10
            n01 = f01 + dt * l00 * f01 + dt * l01 * f11
            n10 = f10 + dt * l10 * f00 + dt * l11 * f10
            n11 = f11 + dt * l10 * f01 + dt * l11 * f11
            F[4 * p], F[4 * p + 1], F[4 * p + 2], F[4 * p + 3] = n00, n01, n10, n11
            J = n00 * n11 - n01 * n10
            volume[p] = J * volume0[p]
            nbad += np.int64(J <= 0.0)
        bad[t] = nbad
'''
ROW = """            dy = ({j} - fy) * h1
            row = base + {j} * stride1
            vx0, vy0, vx1, vy1 = v_new[2 * row], v_new[2 * row + 1], v_new[2 * row + 2], v_new[2 * row + 3]
            vx2, vy2 = v_new[2 * row + 4], v_new[2 * row + 5]
            sx, sy = (wx0 * vx0 + wx1 * vx1) + wx2 * vx2, (wx0 * vy0 + wx1 * vy1) + wx2 * vy2
            tx, ty = (wdx0 * vx0 + wdx1 * vx1) + wdx2 * vx2, (wdx0 * vy0 + wdx1 * vy1) + wdx2 * vy2
            vpx, vpy = vpx + wy{j} * sx, vpy + wy{j} * sy
            b00, b10 = b00 + wy{j} * tx, b10 + wy{j} * ty
            b01, b11 = b01 + (wy{j} * dy) * sx, b11 + (wy{j} * dy) * sy"""


def part_two_passes(sim, plain, repeats: int) -> None:
    ph, p, g, f = sim.phases, sim.particles, sim.grid, sim.frame
    two = _module("g2p_two_passes", TWO_PASSES.format(rows="\n".join(ROW.format(j=j) for j in range(3))))
    x, v, C, F = (a.reshape(-1) for a in (p.x, p.v, ph._affine_matrix, p.F))
    bounds, bad = np.array([0, p.count]), np.zeros(1, dtype=np.int64)
    restore = _restorer(sim)
    calls = {
        "one pass (the solver's)": lambda: _generated_g2p(sim, plain),
        "two passes: gather": lambda: two.gather(
            x, v, C, g.v_new.reshape(-1), f.lower[0], f.lower[1], f.inv_h[0], f.inv_h[1], f.h[0], f.h[1], f.cells[0],
            f.cells[1], f.strides[1], f.offset, ph._d_inv[0], ph._d_inv[1], bounds),
        "two passes: update": lambda: two.update(x, v, C, F, p.volume, p.volume0, MLS_DT, bounds, bad)}
    for call in calls.values():
        restore()
        call()
    restore()
    _print("G2P (USL, MLS) in one pass and in two", _timed(calls, p.count, repeats, restore))
    restore()


DEFERRED_UPDATE = """            if inline:   # the last G2P's particle update, put off until now
                x[p, 0] += dt * v[p, 0]
                x[p, 1] += dt * v[p, 1]
                l00, l01, l10, l11 = C[p, 0, 0], C[p, 0, 1], C[p, 1, 0], C[p, 1, 1]
                f00, f01, f10, f11 = F[p, 0, 0], F[p, 0, 1], F[p, 1, 0], F[p, 1, 1]
                n00 = f00 + dt * l00 * f00 + dt * l01 * f10
                n01 = f01 + dt * l00 * f01 + dt * l01 * f11
                n10 = f10 + dt * l10 * f00 + dt * l11 * f10
                n11 = f11 + dt * l10 * f01 + dt * l11 * f11
                F[p, 0, 0], F[p, 0, 1], F[p, 1, 0], F[p, 1, 1] = n00, n01, n10, n11
                volume[p] = (n00 * n11 - n01 * n10) * volume0[p]
"""
STRESS_IN_P2G = "            if inline:   # the material's stress pass was put off: sigma_p as it computes it\n"
USL_MOVE = """            if mode == USL:
                x[p, 0] += dt * vpx"""


def part_deferred(plain, steps: int = 15, repeats: int = 5) -> None:
    sims = {name: ExplicitMPM(load_scene(mls_block_scene(2, 225, 1, "mls"))) for name in ("generated", "deferred")}
    text = fused_template.source(2, stress=_lines(sims["generated"]))
    if STRESS_IN_P2G not in text or USL_MOVE not in text:
        raise SystemExit("part 4: the template's text changed; update DEFERRED_UPDATE's anchors")
    deferred = text.replace(STRESS_IN_P2G, DEFERRED_UPDATE + STRESS_IN_P2G, 1).replace(
        USL_MOVE, "            if mode == USL and l_is_c:\n                continue\n" + USL_MOVE, 1)
    sims["generated"].phases._kernels = plain
    sims["deferred"].phases._kernels = _module("fused_deferred", deferred)
    for sim in sims.values():   # both on the scalar p2g and g2p, which the deferred variant changes
        sim.phases._splits_mls_g2p = lambda: False
        sim.phases._vectorises_mls_p2g = lambda *arrays: False
    for sim in sims.values():
        for _ in range(5):
            sim.advance(MLS_DT)
    a, b = sims["generated"].particles, sims["deferred"].particles
    same = np.array_equal(a.x, b.x + MLS_DT * b.v) and np.array_equal(a.v, b.v)
    rates = {name: [] for name in sims}
    for _ in range(repeats):
        for name, sim in sims.items():
            rates[name].append(rate(sim, a.count, steps, MLS_DT) / 1e6)
    print(f"whole steps, M particle-steps/s (x, v the same bits, the update pending: {same})")
    for name, r in rates.items():
        print(f"  {name:<28} best {max(r):6.2f}   median {np.median(r):6.2f}")


def part_vectorised(sim, plain, repeats: int) -> None:
    ph, p, g = sim.phases, sim.particles, sim.grid
    from solver.step.fused import _flat

    def vectorised():
        plain.g2p_mls(*_flat(p.x, p.v, ph._affine_matrix, p.F, g.v_new), p.volume, p.volume0, *ph._frame,
                      ph._d_inv, MLS_DT, 1, ph._bad)
    restore = _restorer(sim)
    results = []
    for call in (lambda: _generated_g2p(sim, plain), vectorised):
        restore()
        call()
        results.append([a.copy() for a in (p.x, p.v, p.F, p.volume, ph._affine_matrix)])
    restore()
    same = all(np.array_equal(a, b) for a, b in zip(*results))
    gathers = {name: "\n".join(kernel.inspect_asm().values()).count("vgather")
               for name, kernel in (("g2p", plain.g2p), ("g2p_mls", plain.g2p_mls))}
    _print(f"G2P (USL, MLS): the solver's two kernels (gather instructions {gathers}; the same bits: {same})",
           _timed({"g2p (one scalar pass)": lambda: _generated_g2p(sim, plain), "g2p_mls (vectorised)": vectorised},
                  p.count, repeats, restore))
    restore()


def part_vectorised_p2g(sim, repeats: int) -> None:
    """The solver's two folded MLS P2G kernels on the same state, as FusedPhases._p2g calls them."""
    ph, p, g, c = sim.phases, sim.particles, sim.grid, sim.copies
    from solver.step.fused import _flat
    kernels, acc = ph._kernels, ph.acceleration

    def scalar():
        kernels.p2g(ph._p2g_variants[True, True], p.x, p.v, ph._affine_matrix, p.mass, p.volume, p.stored("stress"),
                    p.F, ph._affine_matrix, p.volume0, ph._stress_parameters, acc, ph._frame, ph._d_inv, g.mass,
                    g.momentum, g.force, c.mass, c.momentum, c.force, ph._bad, MLS_DT)

    def vectorised():
        kernels.p2g_mls(ph._p2g_mls_variants[True, acc.shape[0] == 1], *_flat(p.x, p.v, ph._affine_matrix), p.mass,
                        p.volume, p.stored("stress"), *_flat(p.F, ph._affine_matrix), p.volume0, ph._stress_parameters,
                        *_flat(acc), *ph._frame, ph._d_inv, g.mass, g.momentum, c.mass, c.momentum, ph._bad, MLS_DT)
    results = []
    for call in (scalar, vectorised):
        g.reset()
        call()
        results.append([g.mass.copy(), g.momentum.copy()])
    same = all(np.array_equal(a, b) for a, b in zip(*results))
    vector_log = bool(ph._p2g_mls_variants[True, True][2].ndim - 1)
    _print(f"P2G (folded MLS): the solver's two kernels (the same bits: {same}; log J from log_near_one: {vector_log})",
           _timed({"p2g (scalar)": scalar, "p2g_mls (vectorised in part)": vectorised}, p.count, repeats, g.reset))


def _restorer(sim):
    """A function that puts the particles' x, v, F, V and C_p back as they are now."""
    p, ph = sim.particles, sim.phases
    state = {name: getattr(p, name).copy() for name in ("x", "v", "F", "volume")}
    affine = ph._affine_matrix.copy()

    def restore():
        for name, a in state.items():
            getattr(p, name)[...] = a
        ph._affine_matrix[...] = affine
    return restore


def _lines(sim):
    """The material's stress lines, as solver/step/fused.py hands them to the template."""
    return _material_lines(sim, sim.phases._stress_model, "stress_lines")


def save_block(path: Path) -> None:
    """The 2D block's state as throughput.py saves it for the frameworks' scripts."""
    sim = ExplicitMPM(load_scene(mls_block_scene(2, 225, 1, "mls")))
    p = sim.particles
    save_mls_block(path, p.x, p.v, p, 225, sim.materials[0][0])


def alone(case: str, who: str) -> float:
    """M particle-steps/s of the solver's MLS step or of the numba reference, alone in this process."""
    if case == "2d":
        sim, dt = ExplicitMPM(load_scene(mls_block_scene(2, 225, 1, "mls"))), MLS_DT
        p, model = sim.particles, sim.materials[0][0]
        reference = ReferenceMLS(p.x, p.v, p.mass, p.volume, 225, model.lam, model.mu, 1)
    else:
        sim, dt = ExplicitMPM(load_scene(mpm88_scene(1, "mls"))), MPM88_DT
        p = sim.particles
        reference = ReferenceMPM88(p.x, p.v, p.mass, p.volume, 128, MPM88_BULK, MPM88_GRAVITY, 1)
    stepper = sim if who == "solver" else reference
    for _ in range(3):
        stepper.advance(dt)
    return max(rate(stepper, p.count, 15, dt) for _ in range(3)) / 1e6


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=11)
    parser.add_argument("--remarks", action="store_true", help="print LLVM's loop-vectorizer remarks (part 3)")
    parser.add_argument("--save-block", type=Path, metavar="NPZ",
                        help="write the 2D block's particles as throughput.py hands them to Taichi and Warp, and stop")
    parser.add_argument("--alone", nargs=2, metavar=("CASE", "STEPPER"), help="2d or mpm88; solver or numba")
    args = parser.parse_args()
    numba.set_num_threads(1)
    if args.save_block:
        save_block(args.save_block)
        return 0
    if args.alone:
        case, who = args.alone
        if case not in ("2d", "mpm88") or who not in ("solver", "numba"):
            parser.error("--alone takes 2d or mpm88, then solver or numba")
        print(f"{case} {who} alone, one thread: {alone(case, who):.2f} M particle-steps/s")
        return 0
    sim = ExplicitMPM(load_scene(mls_block_scene(2, 225, 1, "mls")))
    for _ in range(3):
        sim.advance(MLS_DT)
    print(f"2D MLS block, {sim.particles.count:,} particles, one thread")
    part_p2g(sim, args.repeats)
    plain = _module("fused_plain", fused_template.source(2, stress=_lines(sim)))
    part_slp(sim, plain, args.repeats)
    if args.remarks:
        llvm.set_option("", "-pass-remarks=loop-vectorize")
        llvm.set_option("", "-pass-remarks-analysis=loop-vectorize")
    part_two_passes(sim, plain, args.repeats)
    part_deferred(plain)
    part_vectorised(sim, plain, args.repeats)
    part_vectorised_p2g(sim, args.repeats)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
