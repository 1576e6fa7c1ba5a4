"""The fused P2G and G2P kernels (solver/fused.py), written out for one dimension.

One template serves every dimension. `source(dim)` returns the text of a module
with the two kernels, `p2g` and `g2p` (in 2D also `g2p_mls`, MLS's USL pass written so
that LLVM vectorises it: `_g2p_mls`, `p2g_mls`, MLS's folded P2G with its work per
particle vectorised: `_p2g_mls`, and `g2p_kinematics`, MUSL's KINEMATICS pass without MLS
vectorised: `_g2p_kinematics`; in 3D `p2g_lanes` and `g2p_lanes`, MLS's folded P2G and
USL pass with a node's values in the four lanes of one vector, solver/lanes.py: `_p2g_lanes`),
in which the loops over the stencil are nested once per axis and every per-axis and
per-component statement is written out: scalars only, the form the hand-written 2D and 3D
kernels had (a kernel generic over the dimension, with per-axis data in small arrays, was
measured slower; docs/internals.md). `load(dim)` writes that text to
fused_{dim}d_<hash of the text>.py in the user's cache folder
(~/.cache/mpm-solver/fused, else a folder in the system's temporary one) unless
it is there already, and imports it; numba's cache (`cache=True`) keys on that
file's path and modification time, so an unchanged template reuses the compiled
kernels and a changed one compiles once into a new file. Nothing is written into
the package (it may be read-only, and long generated functions do not belong
beside the code that is read), and checkouts with different templates sharing a
cache folder never rewrite each other's files.

The kernels do the floating-point operations of the hand-written ones in the
same order, so the results are the same bits with MPM_FMA=0 (by default, `CONTRACT`,
LLVM may fuse a multiply and the add after it: the same results to round-off): the weight of
node (i, j, k) is wx[i] * (wy[j] * wz[k]) with the product of the outer axes taken once per row
(in 2D wx[i] * wy[j]), gradient component a the same product with g in place of
w on axis a; sums run over the components in order (s00 * dwx + s01 * dwy + s02 *
dwz); F is read whole, n_ab = f_ab + dt l_a0 f_0b + dt l_a1 f_1b + ... written
back, and J = det n expanded along the first row as solver/kernels.py's
`determinant` does.

Names in the emitted code: axis a has the letter c = "xyz"[a] and the loop index
"ijk"[a]; per axis i{c} (first node), f{c} (position in cells from it), w{c},
g{c} (weights and gradients on the S nodes), d{c} = (index - f{c}) h (node minus
particle); per component v{c}, vp{c}, ...; per tensor entry s{a}{b}, l{a}{b}, ....

With the compile-time `fold` (MLS, or APIC with quadratic B-splines, where nothing reads
f_I: the fused plan's `fold`, solver/step/fused.py), P2G scatters m_I and (mv)_I + dt f_I only: dt m_p
b_p joins m_p v_p; with MLS dt V_p sigma_p D_p^-1 is taken from m_p C_p once per particle, as
MLS-MPM codes do; with APIC the momentum and the force share a row's factors: the node's
w (m v + m C (x_I - x_p)) - dt V sigma grad w is wx[i] qa + wdx[i] qb - gx[i] fg, with wdx
= wx (x_I - x_p) along x per particle and qa, qb, fg per row (`_p2g_row`).

With a material's stress lines (`source(..., stress=)`: a model whose stress is a function of
what P2G reads, F_p for neo-Hookean, L_p and V_p / V0_p for the fluid: solver/step/fused.py
`forms_stress`) and the compile-time `inline`, P2G forms sigma_p with them, first in the
particle's body (a log() then spills little), instead of reading the stored stress; the
module is fused_{dim}d_<model>_<digest of its text>. With the compile-time `l_is_c`
(MLS, USL) G2P does not write L_p, which is C_p. With a rate model's update lines
(`source(..., update=)`: linear elasticity, solver/step/fused.py `updates_stress`) and the
compile-time `updates`, the G2P pass that forms L_p updates the stored stress with them.

The particle index p and the node index are unsigned (np.uint64): numba wraps a
negative signed index around (x[-1] is the last row), so every x[p, a], gp[node, a]
with a signed index carries a compare and a select, unless LLVM can prove the index
non-negative, which it cannot for a loop from bounds[t]. Unsigned indices skip the
wrap: measured on the 2D MLS block at one thread, P2G 18 % and G2P 11 % faster, on
mpm88 11 % and 7 %, on the 3D block 5 % and 3-7 %; the same bits (every index is
in range: `_axis` clamps the first node, and a particle outside the grid is stopped
before any G2P).

What is CPU-specific is the thread shell (`_shell`, `_blocked`: a prange over contiguous
particle blocks that calls a function for one block, each scattering into its own copy of the
nodal arrays, see solver/threads.py) and the scatter statements (`_scatter`). A CUDA backend
would emit the same per-particle statements inside a one-thread-per-particle kernel, with
atomic adds in `_scatter` and its own shell.
"""
from __future__ import annotations

import os
import re
import textwrap
from pathlib import Path

import numpy as np

from solver import generated

AXES = "xyz"
LOOPS = "ijk"
HEADER = '''"""Generated by solver/fused_template.py for {dim}D: do not edit (rewritten when the template changes)."""
import numpy as np
from solver.jit import njit, prange

from solver.fused import KINEMATICS, REMAP, USL, _axis, _quadratic, _reduce, _reduce_mass_momentum
from solver.thermal_kernels import takes_grid_temperature
from solver.threads import add_node_copies, block_bounds, own'''
CHUNK = 64   # particles a chunk of `p2g_mls`: its buffers (16 values each in 2D) stay in L1 (64-256 measured: 64)
LOG_CALL = re.compile(r"math\.log\((\w+)\)")
MLS_IMPORTS = """
from solver.fused import _TOUCH as TOUCH
from solver.near_one_log import HIGH as LOG_HIGH, LOW as LOG_LOW, log_near_one

CHUNK = {chunk}""".format(chunk=CHUNK)
LANES_IMPORTS = """
from solver.lanes import lanes_of, load_row, pack_velocity, split, unpack_mass_momentum
from solver.lanes import {operations} as _lane_operations

axpy, add_to_row = _lane_operations.axpy, _lane_operations.add_to_row"""
THERMAL_IMPORTS = """
from solver.fused import _reduce_with
from solver.threads import own_zeroed"""


# -- text helpers ------------------------------------------------------------------

def _each(template: str, dim: int, sep: str = ", ") -> str:
    """template for every axis a (letter c) joined: `_each("m * v[p, {a}]", 2)`."""
    return sep.join(template.format(a=a, c=AXES[a]) for a in range(dim))


def _tensor(template: str, dim: int) -> list[str]:
    """One line per row a: `lhs_a0, lhs_a1 = rhs_a0, rhs_a1` from 'lhs{a}{b} = rhs{a}{b}'."""
    lhs, rhs = template.split(" = ")
    return [", ".join(lhs.format(a=a, b=b) for b in range(dim)) + " = "
            + ", ".join(rhs.format(a=a, b=b, c=AXES[b]) for b in range(dim)) for a in range(dim)]


def _each_line(template: str, dim: int) -> list[str]:
    """template for every axis a (letter c), one line each."""
    return [template.format(a=a, c=AXES[a]) for a in range(dim)]


def _zeros(names: list[str]) -> str:
    return " = ".join(names) + " = 0.0"


def _indent(lines: list[str], level: int) -> list[str]:
    return [" " * (4 * level) + line for line in lines]


def _scatter(array: str, index: str, op: str, value: str) -> str:
    """A particle's contribution added into a nodal array (CPU: the thread's own copy)."""
    return f"{array}[{index}] {op} {value}"


def _outer_product(dim: int, gradient_axis: int | None = None) -> str:
    """The weight of the outer axes 1..dim-1 at (j, k): wy[j] * wz[k]; with gradient_axis a
    the same with g on axis a (gy[j] * wz[k])."""
    return " * ".join(f"{'g' if b == gradient_axis else 'w'}{AXES[b]}[{LOOPS[b]}]" for b in range(1, dim))


def _outer(dim: int, gradient_axis: int | None = None) -> str:
    """How the node loop names an outer product: wo, go1, go2 where it is a product,
    taken once per row (`_products`); the factor itself where there is one (2D)."""
    if dim <= 2:
        return _outer_product(dim, gradient_axis)
    return "wo" if gradient_axis is None else f"go{gradient_axis}"


def _products(dim: int, gradients: bool) -> list[str]:
    """The outer products, once per row: wo = wy[j] * wz[k], go1 = gy[j] * wz[k], go2 = wy[j] * gz[k]."""
    if dim <= 2:
        return []
    return [f"wo = {_outer_product(dim)}"] + [f"go{a} = {_outer_product(dim, a)}" for a in range(1, dim) if gradients]


def _gradient(dim: int) -> list[str]:
    """grad w of node (i, j, k): dwx = gx[i] * wo, dwy = wx[i] * go1, ..."""
    return [f"dwx = gx[i] * {_outer(dim)}"] + [f"dw{AXES[a]} = wx[i] * {_outer(dim, a)}" for a in range(1, dim)]


def _stencil(dim: int, body: list[str], gradients: bool, contact: bool, row_start: tuple = (),
             row_end: tuple = ()) -> list[str]:
    """The loops over the S^dim nodes of a particle's stencil, outer axis first, around
    `body` (which sees node, d{c} of the outer axes and their products, `_outer`); with
    `contact` the nodes are those of the particle's body's field (+ shift, `_field_shift`).
    A row is the S nodes along x at one (j, k): `row_start` runs before them, `row_end` after."""
    lines, level = [], 0
    for a in range(dim - 1, 0, -1):
        c, i = AXES[a], LOOPS[a]
        lines += _indent([f"for {i} in range(S):", f"    d{c} = ({i} - f{c}) * h{a}"], level)
        level += 1
    row = " + ".join(f"(i{AXES[a]} + {LOOPS[a]}) * stride{a}" for a in range(1, dim))
    lines += _indent([f"row = {row} - offset" + (" + shift" if contact else ""), *_products(dim, gradients),
                      *row_start,
                      "for i in range(S):",
                      "    node = np.uint64(row + ix + i)   # (strides[0] is 1: x fastest)"], level)
    return lines + _indent(body, level + 1) + _indent(list(row_end), level)


# By default LLVM may fuse a * b + c into one FMA (rounded once): the step 1.07-1.15x faster
# on the blocks (docs/benchmarks.md, issue 18, fourteenth and fifteenth parts). Only
# contraction, no reassociation: every sum keeps the order written. The results then agree
# with kernels compiled without it (the general backend, a material's own stress pass) to
# round-off, and which products LLVM fuses depends on the CPU it compiles for; MPM_FMA=0
# gives the same bits on every CPU (the regression cases run so). A stress the fused P2G
# forms (`_stress_of_particle`) differs from the one a frame or a checkpoint stores in its
# last bits, so P2G forms it again after such a read (solver/state.py `Particles.derived`):
# what is written never changes the run.
CONTRACT = '{"contract"}'
FMA = "MPM_FMA"


def contracts() -> bool:
    """Whether the kernels are compiled with `CONTRACT`: unless the environment sets MPM_FMA=0."""
    value = os.environ.get(FMA, "1").strip()
    if value not in ("0", "1"):
        raise ValueError(f"{FMA}={value!r}: must be 0 (no contraction: the same bits on every CPU, "
                         "whatever is written) or 1 (FMA contraction: faster, the same results to round-off)")
    return value == "1"


def _shell(signature: str, docstring: str, before: list[str], per_thread: list[str], per_particle: list[str],
           after: list[str], contract: bool, threads: str, prepare: tuple = ()) -> list[str]:
    """A parallel kernel over contiguous blocks of particles (solver/threads.py), each thread's
    block a loop over its particles p after `per_thread` (`_blocked`)."""
    return _blocked(signature, docstring, before,
                    [*per_thread, "bad[t] = -1", "for p in range(np.uint64(lo), np.uint64(hi)):",
                     *_indent(per_particle, 1)], after, contract, threads=threads, prepare=prepare)


def _blocked(signature: str, docstring: str, before: list[str], block: list[str], after: list[str],
             contract: bool, threads: str | None, particles: str = "x.shape[0]", prepare: tuple = ()) -> list[str]:
    """A parallel kernel whose prange over `threads` (an expression, or None: an argument) calls
    `_<name>_block` once per thread with the thread t and its particles lo to hi. The block is a
    function of its own (`before`, then `block`), compiled once for both the kernel's parallel
    form and its serial twin (solver/jit.py), and numba's parallel passes see a loop of one call
    instead of the block's body: a short run of elastic_cube_3d on two threads compiled for 24 s
    against 42 s with the body in the prange, two_disks for 17 s against 21 s, the same bits. The
    block is compiled as a parallel loop's body is (`loop_body`: numpy's error model, no two
    arrays the same memory). The kernel runs `prepare`, the threads, then `after`."""
    options = f", fastmath={CONTRACT}" if contract else ""
    name, parameters = signature.split("(", 1)
    parameters = parameters[:-1]
    arguments = ", ".join(parameter.strip() for parameter in parameters.split(","))
    call = textwrap.wrap(f"_{name}_block(np.int64(t), bounds[t], bounds[t + 1], {arguments})", 104,
                         subsequent_indent="        ")
    return ["", "", f"@njit(cache=True, loop_body=True{options})",
            f"def _{name}_block(t, lo, hi, {parameters}):",
            f'    """Thread t\'s block of `{name}`: particles lo to hi."""',
            *_indent([*before, *block], 1),
            "", "", f"@njit(parallel=True, cache=True{options})", f"def {signature}:", f'    """{docstring}"""',
            *_indent([*([f"threads = {threads}"] if threads else []), *prepare], 1),
            f"    bounds = block_bounds({particles}, threads)",
            "    for t in prange(threads):   # (t: unsigned; the block takes a signed t, as its serial twin's is)",
            *_indent(call, 2),
            *_indent(after, 1)]


def _frame(dim: int) -> list[str]:
    """The frame, with the spacing and strides the node loops read as scalars: there numba
    cannot tell the frame's arrays from the nodal arrays written, and reads them again at every
    node (G2P 4 % slower, mpm88 at one thread). The per-particle `_axis` keeps its reads
    (as scalars too, held across the loop, G2P lost that 4 % again)."""
    return ["lower, h, inv_h, cells, strides, offset = frame",
            f"{_each('h{a}', dim)} = {_each('h[{a}]', dim)}",
            *[f"stride{a} = strides[{a}]" for a in range(1, dim)]]


def _axes(dim: int, ok: bool) -> list[str]:
    """First node, position in cells, weights and gradients per axis (and whether inside)."""
    return [f"{'ok' + c if ok else '_'}, i{c}, f{c}, w{c}, g{c} = _axis(S, x[p, {a}], lower[{a}], inv_h[{a}], cells[{a}])"
            for a, c in enumerate(AXES[:dim])]


# -- P2G ---------------------------------------------------------------------------

def _p2g_node(dim: int, thermal: bool, contact: bool) -> list[str]:
    """What one particle adds to one node: mass, momentum (APIC term), force; `fold`:
    mass and q = mv + dt f only (the force is in mv and mc, `_p2g_particle`); with
    `thermal` the conduction's C_I, (C T)_I, Q_I (`_heat_p2g_node`; never folded); with
    `contact` the contact's presence and normals (`_contact_p2g_node`; never folded)."""
    def force(a):
        return _each(f"s{a}{{a}} * dw{{c}}", dim, " - ")
    return [
        f"w = wx[i] * {_outer(dim)}",
        "if affine:",
        "    dx = (i - fx) * h0",
        "if fold:",
        "    pass",
        "elif mls:   # w (x_I - x_p); D_p^-1 is in s (the MLS gradient, solver/transfer.py)",
        *_indent(_each_line("dw{c} = w * d{c}", dim), 1),
        "else:",
        *_indent(_gradient(dim), 1),
        f"{_each('p{c}', dim)} = {_each('mv{c}', dim)}",
        "if affine:",
        *[f"    p{AXES[a]} = r{AXES[a]} + mc{a}0 * dx" for a in range(dim)],
        _scatter("gm", "node", "+=", "w * m"),
        "if fold and not mls:   # w (m v + dt m b + m C (x_I - x_p)) - dt V sigma grad w (`_p2g_row`)",
        *[f"    {_scatter('gp', f'node, {a}', '+=', f'wx[i] * qa{AXES[a]} + wdx[i] * qb{AXES[a]} - gx[i] * fg{AXES[a]}')}"
          for a in range(dim)],
        "else:",
        *[f"    {_scatter('gp', f'node, {a}', '+=', f'w * p{AXES[a]}')}" for a in range(dim)],
        "if fold:",
        "    pass",
        "elif mls and loaded:",
        *[f"    {_scatter('gf', f'node, {a}', '+=', f'w * mb{AXES[a]} - {force(a)}')}" for a in range(dim)],
        "elif mls:",
        *[f"    {_scatter('gf', f'node, {a}', '-=', force(a).replace(' - ', ' + '))}" for a in range(dim)],
        "elif loaded:   # w mb - sigma grad w, its row factors taken once (`_p2g_row`)",
        *[f"    {_scatter('gf', f'node, {a}', '+=', f'wx[i] * fw{AXES[a]} - gx[i] * fg{AXES[a]}')}"
          for a in range(dim)],
        "else:",
        *[f"    {_scatter('gf', f'node, {a}', '-=', f'wx[i] * fo{AXES[a]} + gx[i] * fg{AXES[a]}')}"
          for a in range(dim)],
        *(_heat_p2g_node(dim) if thermal else []),
        *(_contact_p2g_node(dim) if contact else []),
    ]


def _heat_p2g_node(dim: int) -> list[str]:
    """Conduction's P2G (Algorithm 8, lines 3-7) as solver/thermal_kernels.py's `p2g` does it:
    C_I += w m c, (C T)_I += w m c T, Q_I += V (0 + q_0 dw_0 + q_1 dw_1 ...) with the
    gradient the general backend's stencil holds (MLS: w D_p^-1 (x_I - x_p); here dw is
    w (x_I - x_p), D_p^-1 being in s)."""
    return [
        "if mls:",
        *_indent(_each_line("tg{c} = dw{c} * d_inv{a}", dim), 1),
        "else:",
        f"    {_each('tg{c}', dim)} = {_each('dw{c}', dim)}",
        _scatter("th", "node, 0", "+=", "w * mcap"),
        _scatter("th", "node, 1", "+=", "w * mct"),
        _scatter("th", "node, 2", "+=", f"vol * (0.0 + {_each('q{c} * tg{c}', dim, ' + ')})"),
    ]


def _contact_p2g_node(dim: int) -> list[str]:
    """The contact's sums per field (solver/contact.py's `fields_and_normals`): presence_I +=
    V_p w and the mass-gradient normal gradient_I += m_p grad w ([R] 5.12), with the gradient
    the general backend's stencil holds (MLS: w D_p^-1 (x_I - x_p); dw here is w (x_I - x_p))."""
    return [
        _scatter("pr", "node", "+=", "vol * w"),
        "if mls:",
        *_indent([_scatter("gr", f"node, {a}", "+=", f"m * (dw{AXES[a]} * d_inv{a})") for a in range(dim)], 1),
        "else:",
        *_indent([_scatter("gr", f"node, {a}", "+=", f"m * dw{AXES[a]}") for a in range(dim)], 1),
    ]


def _field_shift(contact: bool) -> list[str]:
    """The first entry of the particle's body's field in the nodal arrays (solver/contact.py)."""
    return ["shift = field_of_body[body[p]] * n_nodes"] if contact else []


def _stress_of_particle(dim: int, stress: tuple | None) -> list[str]:
    """sig{a}{b}, the in-plane entries of sigma_p: read from the stored stress, or, with `stress`
    (a material's name, lines and number of parameters: solver/step/fused.py `forms_stress`)
    and the compile-time `inline`, formed by the material's lines, which see f{a}{b} (F_p), fj
    (det F_p, as solver/kernels.py's `determinant`), l{a}{b} (L_p), vol_p and vol0_p (V_p, V0_p)
    and q0, q1, ... (its parameters). What a model's lines do not use, the compiler drops."""
    stored = _tensor("sig{a}{b} = stress[p, {a}, {b}]", dim)
    if stress is None:
        return stored
    return ["if inline:   # the material's stress pass was put off: sigma_p as it computes it",
            *_indent(_tensor("f{a}{b} = F[p, {a}, {b}]", dim), 1),
            f"    fj = {_determinant(list(range(dim)), list(range(dim)), 'f')}",
            *_indent(_tensor("l{a}{b} = L[p, {a}, {b}]", dim), 1),
            "    vol_p, vol0_p = volume[p], volume0[p]",
            *_indent(list(stress[1]), 1),
            "else:",
            *_indent(stored, 1)]


def _p2g_row(dim: int) -> list[str]:
    """What is the same for the S nodes of a row: the particle's affine momentum m v_p + m C_p
    (x_I - x_p) without its x term (a product and a sum per node fewer: P2G 1.05-1.12x with
    MLS); and, without MLS, the force's factors. With grad w = (gx[i] wo, wx[i] go1, ...) the
    node's w m b_p - V sigma_p grad w is wx[i] fw - gx[i] fg: fg = V sigma_a0 wo, fo = V
    (sigma_a1 go1 + ...), fw = m b_a wo - fo. The folded APIC momentum (dt in s, dt m b in mv)
    takes qa = wo r - fo and qb = wo m C_a0 once per row."""
    force = [line for a, c in enumerate(AXES[:dim]) for line in (
        f"fg{c} = s{a}0 * {_outer(dim)}",
        f"fo{c} = " + " + ".join(f"s{a}{b} * {_outer(dim, b)}" for b in range(1, dim)),
        f"fw{c} = mb{c} * {_outer(dim)} - fo{c}")]
    folded = [line for a, c in enumerate(AXES[:dim]) for line in (
        f"qa{c} = {_outer(dim)} * r{c} - fo{c}",
        f"qb{c} = {_outer(dim)} * mc{a}0")]
    return _momentum_row(dim) + force + ["if fold and not mls:", *_indent(folded, 1)]


def _momentum_row(dim: int) -> list[str]:
    """r{c} = m v_p + m C_p (x_I - x_p) along the outer axes: what a row's nodes share of it."""
    return [f"r{c} = mv{c}" + "".join(f" + mc{a}{b} * d{AXES[b]}" for b in range(1, dim))
            for a, c in enumerate(AXES[:dim])]


def _p2g_particle(dim: int, thermal: bool, contact: bool, stress: tuple | None, lanes: bool = False) -> list[str]:
    mc = [f"mc{a}{b}" for a in range(dim) for b in range(dim)]
    return [
        *_stress_of_particle(dim, stress),   # first: little is live across its log()
        *_axes(dim, ok=True),
        f"if not ({_each('ok{c}', dim, ' and ')}):      # (no break: an early exit slows the whole loop)",
        "    if bad[t] < 0:",
        "        bad[t] = p",
        "    continue",
        "m = mass[p]",
        "ap = np.uint64(0) if shared_acc else p",
        f"{_each('mb{c}', dim)} = {_each('m * acc[ap, {a}]', dim)}",
        f"{_each('mv{c}', dim)} = {_each('m * v[p, {a}]', dim)}",
        "vol = volume[p]",
        "if fold:   # dt f_I into the momentum: w (m v + dt m b) + m C (x_I - x_p) w - dt V sigma grad w",
        "    if loaded:   # (without a body force dt m b is +0: adding it would change no sum)",
        *_indent(_each_line("mv{c} += dt * mb{c}", dim), 2),
        "    if mls:   # (MLS: grad w = w D^-1 (x_I - x_p), so that dt V sigma D^-1 joins m C)",
        *_indent(_tensor("s{a}{b} = dt * (vol * sig{a}{b} * d_inv{b})", dim), 2),
        "    else:",
        *_indent(_tensor("s{a}{b} = dt * (vol * sig{a}{b})", dim), 2),
        "elif mls:",
        *_indent(_tensor("s{a}{b} = vol * sig{a}{b} * d_inv{b}", dim), 1),
        "else:",
        *_indent(_tensor("s{a}{b} = vol * sig{a}{b}", dim), 1),
        _zeros(mc) + "   # m_p C_p (C holds one placeholder row without APIC)",
        "if affine:",
        *_indent(_tensor("mc{a}{b} = m * C[p, {a}, {b}]", dim), 1),
        "if fold and mls:",
        *_indent(_tensor("mc{a}{b} = mc{a}{b} - s{a}{b}", dim), 1),
        *(["mcap = m * capacity[p]   # 0 for a material without conduction: it adds zeros (the general",
           "mct = mcap * T[p]        # kernel skips it: the same sums; a test per node cost 12 % of P2G)",
           f"{_each('q{c}', dim)} = {_each('heat_flux[p, {a}]', dim)}"] if thermal else []),
        *_field_shift(contact),
        *(_lanes_stencil(dim) if lanes else [
            "if fold and not mls:   # w (x_I - x_p) along x, for the row factors of the folded APIC momentum",
            "    wdx = wx[0] * ((0 - fx) * h0), wx[1] * ((1 - fx) * h0), wx[2] * ((2 - fx) * h0)",
            *_stencil(dim, _p2g_node(dim, thermal, contact), gradients=True, contact=contact,
                      row_start=_p2g_row(dim))]),
    ]


def _p2g(dim: int, thermal: bool, contact: bool, stress: tuple | None, contract: bool) -> list[str]:
    return _shell(
        "p2g(variant, x, v, C, mass, volume, stress, F, L, volume0, material, acc, frame, d_inv,\n"
        "        grid_mass, grid_mom, grid_force, copies_mass, copies_mom, copies_force, bad, dt"
        + (",\n        capacity, T, heat_flux, heat, copies_heat" if thermal else "")
        + (",\n        body, field_of_body, n_nodes, presence, gradient, copies_presence, copies_gradient"
           if contact else "") + ")",
        "m_I, (mv)_I (with the APIC term m w C (x_I - x_p) when `affine`) and f_I =\n"
        "    sum_p m_p w b_p - V_p sigma_p grad w (MLS: w D_p^-1 (x_I - x_p) for grad w). bad[t]: first\n"
        "    particle of block t outside the grid. `fold` (MLS; APIC): f_I is not formed, dt f_I is\n"
        "    added into (mv)_I instead (grid_force untouched).\n\n"
        "    variant: (support, affine, loaded, mls, fold, inline) constants; frame: (lower, h, inv_h,\n"
        "    cells, strides, offset); d_inv: D_p^-1 per axis (APIC, MLS); copies_*: the nodal arrays of\n"
        "    the other threads. `inline`: sigma_p is formed from F, L, V, V0 and the material's\n"
        "    parameters `material` (where the module has a material's lines), not read from `stress`."
        + ("\n\n    Conduction: heat (n, 3), zeroed here, gets C_I, (C T)_I and Q_I^int from c_p, T_p, q_p."
           if thermal else "")
        + ("\n\n    Contact (a field per body): every node is node + field_of_body[body[p]] * n_nodes;\n"
           "    presence gets V_p w and gradient m_p grad w per field (zeroed by the caller)." if contact else ""),
        ["support, affine_, loaded_, mls_, fold_, inline_ = variant",
         *_parameters(stress),
         *_frame(dim),
         f"{_each('d_inv{a}', dim)} = {_each('d_inv[{a}]', dim)}",
         "shared_acc = acc.shape[0] == 1"],
        ["S, affine, loaded, mls = support.ndim - 1, affine_.ndim == 2, loaded_.ndim == 2, mls_.ndim == 2"
         "   # compile-time constants",
         "fold, inline = fold_.ndim == 2, inline_.ndim == 2",
         "gm, gp = own(t, grid_mass, copies_mass), own(t, grid_mom, copies_mom)",
         "gf = grid_force if fold else own(t, grid_force, copies_force)",
         *(["th = own_zeroed(t, heat, copies_heat)"] if thermal else []),
         *(["pr, gr = own(t, presence, copies_presence), own(t, gradient, copies_gradient)"] if contact else [])],
        _p2g_particle(dim, thermal, contact, stress),
        ["if variant[4].ndim == 2:   # (fold_)",
         "    _reduce_mass_momentum(DIMS, grid_mass, grid_mom, copies_mass, copies_mom)",
         "else:",
         *_p2g_reduce(thermal, contact)], contract, threads="copies_mass.shape[0] + 1")


def _parameters(lines: tuple | None) -> list[str]:
    """q0, q1, ... = the material's parameters (`material`), read once before the threads' loop."""
    if lines is None:
        return []
    names = [f"q{k}" for k in range(lines[2])]
    values = ", ".join(f"material[{k}]" for k in range(lines[2]))
    return [f"{', '.join(names)}{',' if len(names) == 1 else ''} = {values}"]


def _p2g_reduce(thermal: bool, contact: bool) -> list[str]:
    """The unfolded P2G's sum of the threads' copies: one parallel loop over the nodes for all
    the arrays it scattered (each loop ends in a wait for the slowest thread)."""
    if contact:   # (the presence as (n, 1): `_reduce_with` takes (n, k) arrays)
        return ["    _reduce_with(grid_mass, grid_mom, grid_force, presence.reshape((presence.shape[0], 1)), gradient,",
                "                 copies_mass, copies_mom, copies_force,",
                "                 copies_presence.reshape((copies_presence.shape[0], copies_presence.shape[1], 1)),",
                "                 copies_gradient)"]
    if thermal:   # (with an empty second array)
        return ["    _reduce_with(grid_mass, grid_mom, grid_force, heat, heat[:, :0], copies_mass, copies_mom,",
                "                 copies_force, copies_heat, copies_heat[:, :, :0])"]
    return ["    _reduce(DIMS, grid_mass, grid_mom, grid_force, copies_mass, copies_mom, copies_force)"]


# -- MLS's P2G, vectorised in part ----------------------------------------------------



def _p2g_mls_fields(dim: int) -> list[str]:
    """What the vectorised pass hands the scatter per particle (rows of `buf`): f{c}, the weights,
    m_p, m v_p (+ dt m b_p) and m C_p - dt V_p sigma_p D_p^-1."""
    return ([f"f{c}" for c in AXES[:dim]] + [f"w{c}{n}" for c in AXES[:dim] for n in range(3)] + ["m"]
            + [f"mv{c}" for c in AXES[:dim]] + [f"mc{a}{b}" for a in range(dim) for b in range(dim)])


def _p2g_mls_stress(dim: int, stress: tuple | None, vector: bool) -> list[str]:
    """sig{a}{b} as `_stress_of_particle` forms it, from the flat arrays. `vector`: each math.log(v)
    of the material's lines is `log_near_one(v)` where that is libm's log (solver/near_one_log.py,
    the compile-time `vector_log`) and v lies in its interval; `far` counts the particles where it
    does not (their values are formed again with math.log: `_p2g_mls_chunk`)."""
    stored = _stress_of_particle(dim, None)
    if stress is None:
        return stored
    lines = list(stress[1])
    logged = _logged(stress)
    if vector:
        lines = [LOG_CALL.sub(r"(log_near_one(\1) if vector_log else math.log(\1))", line) for line in lines]
        lines += [f"far += vector_log and not ({_near_one(logged)})"] if logged else []
    elif logged:
        lines += [f"if vector_log and {_near_one(logged)}:", "    continue   # (the vectorised pass formed it)"]
    flat = [f"f{a}{b} = F[{_flat('p', dim * dim, dim * a + b)}]" for a in range(dim) for b in range(dim)]
    return ["if inline:",
            *_indent(flat, 1),
            f"    fj = {_determinant(list(range(dim)), list(range(dim)), 'f')}",
            *_indent([f"l{a}{b} = L[{_flat('p', dim * dim, dim * a + b)}]" for a in range(dim) for b in range(dim)], 1),
            "    vol_p, vol0_p = volume[p], volume0[p]",
            *_indent(lines, 1),
            "else:",
            *_indent(stored, 1)]


def _near_one(names: list[str]) -> str:
    return " & ".join(f"({name} >= LOG_LOW) & ({name} < LOG_HIGH)" for name in names) or "True"


def _p2g_mls_axes(dim: int) -> list[str]:
    """`_axis` for quadratic B-splines written inline (branch-free: LLVM vectorises it), `inside` whether
    the particle is in the grid; the first node 0 outside, as `_axis` gives it."""
    lines = [line for a, c in enumerate(AXES[:dim]) for line in (
        f"at{c} = (x[{_flat('p', dim, a)}] - lower{a}) * inv_h{a}",
        f"ok{c} = (at{c} >= 0.5 - TOUCH) & (at{c} <= cells{a} - 0.5 + TOUCH)",
        f"i{c} = min(max(int(at{c} - 0.5), 0), cells{a} - 2) if ok{c} else 0")]
    return lines + [f"inside = {_each('ok{c}', dim, ' & ')}"]


def _p2g_mls_particle(dim: int, stress: tuple | None, vector: bool) -> list[str]:
    """`_p2g_particle`'s work on particle p = c + k (MLS, folded, quadratic B-splines) up to the
    scatter, in its order (the same bits), into column k of the buffers."""
    fields = _p2g_mls_fields(dim)
    return [
        *_p2g_mls_stress(dim, stress, vector),
        *_p2g_mls_axes(dim),
        *[line for a, c in enumerate(AXES[:dim]) for line in (f"f{c} = at{c} - i{c}", f"w{c} = _quadratic(f{c})")],
        *(["outside += not inside"] if vector else []),
        "m = mass[p]",
        "if shared_acc:   # (a compile-time constant: a load from a selected index keeps the loop scalar)",
        f"    {_each('mb{c}', dim)} = {_each('m * acc0{c}', dim)}",
        "else:",
        f"    {_each('mb{c}', dim)} = {_each('m * acc[' + _flat('p', dim, '{a}') + ']', dim)}",
        f"{_each('mv{c}', dim)} = {_each('m * v[' + _flat('p', dim, '{a}') + ']', dim)}",
        "vol = volume[p]",
        "if loaded:",
        *_indent(_each_line("mv{c} += dt * mb{c}", dim), 1),
        *_tensor("s{a}{b} = dt * (vol * sig{a}{b} * d_inv{b})", dim),
        *[f"mc{a}{b} = m * C[{_flat('p', dim * dim, dim * a + b)}] - s{a}{b}" for a in range(dim) for b in range(dim)],
        *[f"first[{a}, k] = i{c}" for a, c in enumerate(AXES[:dim])],
        *[f"buf[{n}, k] = " + (f"w{name[1]}[{name[2]}]" if name[0] == "w" else name) for n, name in enumerate(fields)],
    ]


def _logged(stress: tuple | None) -> list[str]:
    """The names the material's lines take the log of (`math.log(name)`)."""
    return sorted({name for line in (stress[1] if stress else ()) for name in LOG_CALL.findall(line)})


def _p2g_mls_scatter(dim: int, lanes: bool) -> list[str]:
    """The nodes of particle c + k from the buffers, as `_p2g_node` adds them with fold and mls;
    with `lanes` a node's (m, mv_x, mv_y, 0) as one float64x4 into the thread's rows `gl`
    (`_lanes_stencil`)."""
    fields = _p2g_mls_fields(dim)
    weights = [f"w{c} = " + ", ".join(f"buf[{fields.index(f'w{c}{n}')}, k]" for n in range(3)) for c in AXES[:dim]]
    reads = [*[f"i{c} = first[{a}, k]" for a, c in enumerate(AXES[:dim])],
             *[f"{name} = buf[{n}, k]" for n, name in enumerate(fields) if not name.startswith("w")], *weights]
    if lanes:
        return reads + _lanes_stencil(dim)
    node = [f"w = wx[i] * {_outer(dim)}", "dx = (i - fx) * h0",
            *[f"p{AXES[a]} = r{AXES[a]} + mc{a}0 * dx" for a in range(dim)],
            _scatter("gm", "node", "+=", "w * m"),
            *[_scatter("gp", f"node, {a}", "+=", f"w * p{AXES[a]}") for a in range(dim)]]
    return reads + _stencil(dim, node, gradients=False, contact=False, row_start=_momentum_row(dim))


def _p2g_mls_chunk(dim: int, stress: tuple | None, lanes: bool) -> list[str]:
    """One chunk of a thread's block: the vectorised pass, the rare passes after it (log outside its
    interval, a particle outside the grid), the scalar scatter."""
    fix = ["if far:   # (a log outside log_near_one's interval) formed again with math.log",
           "    for k in range(n):",
           "        p = c + k",
           *_indent(_p2g_mls_particle(dim, stress, vector=False), 2)] if _logged(stress) else []
    zeroed = [f"buf[{n}, k] = 0.0" for n in range(len(_p2g_mls_fields(dim)))]
    return [
        "c = start + chunk * CHUNK   # (c >= 0 known: LLVM vectorises the loop below)",
        "n = min(CHUNK, total - chunk * CHUNK)",
        "far = outside = 0",
        "for k in range(n):",
        "    p = c + k",
        *_indent(_p2g_mls_particle(dim, stress, vector=True), 1),
        *fix,
        "if outside:   # (the step fails) the first such particle; the others add nothing",
        "    for k in range(n):",
        "        p = c + k",
        *_indent(_p2g_mls_axes(dim), 2),
        "        if not inside:",
        "            if bad[t] < 0:",
        "                bad[t] = p",
        *_indent(zeroed, 3),
        "for k in range(n):",
        *_indent(_p2g_mls_scatter(dim, lanes), 1),
    ]


def _flat_frame(dim: int) -> list[str]:
    """The frame and D_p^-1 as scalars, for the vectorised kernels, which take the frame unpacked."""
    return [f"{_each('h{a}', dim)} = {_each('h[{a}]', dim)}", *[f"stride{a} = strides[{a}]" for a in range(1, dim)],
            f"{_each('lower{a}', dim)} = {_each('lower[{a}]', dim)}",
            f"{_each('inv_h{a}', dim)} = {_each('inv_h[{a}]', dim)}",
            f"{_each('cells{a}', dim)} = {_each('cells[{a}]', dim)}",
            f"{_each('d_inv{a}', dim)} = {_each('d_inv[{a}]', dim)}"]


def _p2g_mls(dim: int, stress: tuple | None, contract: bool, lanes: bool = False) -> list[str]:
    """`p2g` for MLS with the force folded (`fold`) and quadratic B-splines, its work per particle
    in a loop LLVM vectorises: per chunk of CHUNK particles, sigma_p (with log_near_one for log J:
    a call to libm keeps a loop scalar), the weights, m v_p and m C_p - dt V sigma_p D_p^-1 for 8
    particles at a time into small buffers, then the scatter, which cannot be vectorised (the
    particles of a loop add into the same nodes), reads them. The same bits as `p2g`.
    `lanes`: `p2g_mls_lanes`, the scatter adding a node's values as one float64x4 into the
    thread's rows of `lanes` (threads, n, 4; zeroed here), summed into the grid in thread order
    as `p2g_lanes` does: the same bits again."""
    frame = _flat_frame(dim)
    name, targets = ("p2g_mls_lanes", "lanes") if lanes else ("p2g_mls", "copies_mass, copies_mom")
    return _blocked(
        f"{name}(variant, x, v, C, mass, volume, stress, F, L, volume0, material, acc, lower, h, inv_h, cells,\n"
        f"            strides, offset, d_inv, grid_mass, grid_mom, {targets}, bad, dt)",
        "m_I and (mv)_I + dt f_I as `p2g` with `fold` and `mls` forms them (the same bits), on flat\n"
        "    views: x, v and acc dim entries a row (acc one row when shared), C, F and L dim^2. variant:\n"
        "    (loaded, inline, vector_log, shared_acc) constants; vector_log: log_near_one is libm's log\n"
        "    here; shared_acc: acc is one row for all.\n"
        "    bad[t]: first particle of block t outside the grid.",
        ["loaded_, inline_, vector_log_, shared_acc_ = variant",
         *_parameters(stress),
         *frame,
         f"{_each('acc0{c}', dim)} = ({_each('acc[{a}]', dim)}) if acc.shape[0] >= {dim} else ({_each('0.0', dim)})"],
        ["S, loaded, inline = 3, loaded_.ndim == 2, inline_.ndim == 2   # compile-time constants",
         "vector_log, shared_acc = vector_log_.ndim == 2, shared_acc_.ndim == 2",
         *(["gl = lanes[t]", "gl[:, :] = 0.0   # (by the thread that adds into them)"] if lanes else
           ["gm, gp = own(t, grid_mass, copies_mass), own(t, grid_mom, copies_mom)"]),
         f"first, buf = np.empty(({dim}, CHUNK), dtype=np.int64), np.empty(({len(_p2g_mls_fields(dim))}, CHUNK))",
         "bad[t] = -1",
         "start = max(lo, 0)",
         "total = hi - start",
         "for chunk in range((total + CHUNK - 1) // CHUNK):",
         *_indent(_p2g_mls_chunk(dim, stress, lanes), 1)],
        ["unpack_mass_momentum(grid_mass, grid_mom, lanes)" if lanes else
         "_reduce_mass_momentum(DIMS, grid_mass, grid_mom, copies_mass, copies_mom)"], contract,
        threads="lanes.shape[0]" if lanes else "copies_mass.shape[0] + 1", particles="volume.shape[0]")


# -- G2P ---------------------------------------------------------------------------

def _g2p_gather(dim: int, thermal: bool) -> list[str]:
    """What one node adds to its row's sums (`_g2p_row_end`): the x weights times the node's
    velocity (s{c}), times x_I - x_p as well (t{c}, `wdx`), the x gradients times it (u{c}),
    the x weights times its FLIP increment (e{c}); with `thermal` the conduction's gathers
    (`_heat_g2p_gather`), which take the node's whole weight w."""
    return [
        f"{_each('v{c}', dim)} = {_each('v_new[node, {a}]', dim)}",
        *_each_line("s{c} += wx[i] * v{c}", dim),
        "if affine and (mls or mode != KINEMATICS):   # B_p (MLS: also the L_p of the remapped velocity)",
        *_indent(_each_line("t{c} += wdx[i] * v{c}", dim), 1),
        "if mode != KINEMATICS and blend:",
        *_indent(_each_line("e{c} += wx[i] * (v{c} - v_old[node, {a}])", dim), 1),
        "if mode != REMAP and not mls:",
        *_indent(_each_line("u{c} += gx[i] * v{c}", dim), 1),
        *([f"w = wx[i] * {_outer(dim)}", "dx = (i - fx) * h0",
           "if mode == KINEMATICS and not mls:", *_indent(_gradient(dim), 1), *_heat_g2p_gather(dim)]
          if thermal else []),
    ]


def _g2p_row_start(dim: int) -> list[str]:
    return [_zeros([f"{n}{c}" for n in "stue" for c in AXES[:dim]])]


def _g2p_row_end(dim: int) -> list[str]:
    """The row's sums into the particle's: the weights factor into x and the outer axes (w =
    wx[i] wo, grad w = (gx[i] wo, wx[i] go1, ...)), so a node's terms are summed along x first
    and multiplied by the row's outer factor once (G2P 1.10-1.35x:
    `git show 63f7e3a^:docs/benchmarks.md`, "Speed, eleventh part")."""
    wo = _outer(dim)
    return [
        "if mode != KINEMATICS:",
        *_indent(_each_line(f"vp{{c}} += {wo} * s{{c}}", dim), 1),
        "    if blend:",
        *_indent(_each_line(f"dv{{c}} += {wo} * e{{c}}", dim), 2),
        "if affine and (mls or mode != KINEMATICS):",
        *[f"    b{a}0 += {wo} * t{AXES[a]}" for a in range(dim)],
        *[f"    b{a}{b} += ({wo} * d{AXES[b]}) * s{AXES[a]}" for a in range(dim) for b in range(1, dim)],
        "if mode != REMAP and not mls:",
        *[f"    l{a}0 += {wo} * u{AXES[a]}" for a in range(dim)],
        *[f"    l{a}{b} += {_outer(dim, b)} * s{AXES[a]}" for a in range(dim) for b in range(1, dim)],
    ]


def _heat_g2p_gather(dim: int) -> list[str]:
    """Conduction's gathers, in the order of solver/thermal_kernels.py's sums: the REMAP pass
    takes dT_p = sum w (T~_I - T_I) (Algorithm 8, line 12; the hook formed T~_I - T_I, the same
    bits as the difference taken here, one read less), and sum w T~_I with the weight on held
    nodes, which decide between the two (thermal_kernels.takes_grid_temperature); the
    KINEMATICS pass, which runs after the remapped T_I^{t+dt} was formed and still has x_p^t, the flux's sum grad w T_I
    (line 15; MLS: its gradient w D_p^-1 (x_I - x_p), as the general stencil holds it)."""
    return [
        "if mode == REMAP:",
        "    dT += w * T_change[node]",
        "    tg += w * T_grid[node]",
        "    reach += w * held[node]",
        "if mode == KINEMATICS and kp != 0.0:",
        "    if mls:",
        *_indent(_each_line("dw{c} = w * d{c} * d_inv{a}", dim), 2),
        *_indent(_each_line("tq{c} += dw{c} * T_grid[node]", dim), 1),
    ]


def _g2p_remap(dim: int, thermal: bool, contact: bool) -> list[str]:
    """MUSL: the particle's new momentum m w (v_p + C_p (x_I - x_p)) back to the grid (with
    `thermal`: T_p += dT_p, and w m c T_p into `remapped`, Algorithm 8 lines 12-13)."""
    node = [
        f"mw = m * (wx[i] * {_outer(dim)})",
        f"{_each('p{c}', dim)} = {_each('vr{c}', dim)}",
        "if affine:",
        "    dx = (i - fx) * h0",
        *[f"    p{AXES[a]} += {_each(f'cr{a}{{a}} * d{{c}}', dim, ' + ')}" for a in range(dim)],
        *[_scatter("gp", f"node, {a}", "+=", f"mw * p{AXES[a]}") for a in range(dim)],
        *([_scatter("tr", "node", "+=", f"(wx[i] * {_outer(dim)}) * mct")] if thermal else []),
    ]
    heat = ["    mcap = m * capacity[p]",
            "    if mcap != 0.0:   # a material without conduction keeps its T_p (and maps back zeros)",
            "        T[p] = takes_grid_temperature(reach, T[p], dT, tg)",
            "    mct = mcap * T[p]"]
    return [
        "if mode == REMAP:",
        f"    {_each('rate[p, {a}]', dim)} = {_each('vp{c}', dim)}",
        "    m = mass[p]",
        # v_p and C_p as scalars: read in the node loop, they were loaded again after every
        # scatter (numba cannot tell v and C from the nodal array written)
        f"    {_each('vr{c}', dim)} = {_each('v[p, {a}]', dim)}",
        "    if affine:",
        *_indent(_tensor("cr{a}{b} = C[p, {a}, {b}]", dim), 2),
        *(heat if thermal else []),
        *_indent(_stencil(dim, node, gradients=False, contact=contact), 1),
        "    continue",
    ]


def _deformation_gradient(dim: int) -> list[str]:
    """F <- (I + dt L) F: n_ab = f_ab + dt l_a0 f_0b + dt l_a1 f_1b + ..., with f the old F."""
    return [*_tensor("f{a}{b} = F[p, {a}, {b}]", dim),
            *[f"n{a}{b} = f{a}{b} + " + " + ".join(f"dt * l{a}{c} * f{c}{b}" for c in range(dim))
              for a in range(dim) for b in range(dim)],
            *_tensor("F[p, {a}, {b}] = n{a}{b}", dim)]


def _determinant(rows: list[int], columns: list[int], name: str = "n") -> str:
    """det of the new F (n) expanded along its first row, as solver/kernels.py's `determinant`:
    n00 * (n11 * n22 - n12 * n21) - n01 * (...) + n02 * (...); in 2D n00 * n11 - n01 * n10."""
    if len(rows) == 1:
        return f"{name}{rows[0]}{columns[0]}"
    text = ""
    for n, c in enumerate(columns):
        minor = _determinant(rows[1:], [d for d in columns if d != c], name)
        term = f"{name}{rows[0]}{c} * " + (f"({minor})" if len(rows) > 2 else minor)
        text += term if n == 0 else (" - " if n % 2 else " + ") + term
    return text


def _stress_update(update: tuple | None) -> list[str]:
    """With `update` (a material's name, lines and number of parameters: solver/step/fused.py
    `updates_stress`) and the compile-time `updates`, the material's stress update from the L_p
    just formed, in place: its lines see l{a}{b}, dt, q0, q1, ... (its parameters) and add into
    stress[p, a, b] as its own pass would, in its order (the same bits; to round-off with `CONTRACT`)."""
    if update is None:
        return []
    return ["if updates:   # the material's pass, put here: its stress read and written once, L_p not read back",
            *_indent(list(update[1]), 1)]


def _g2p_particle(dim: int, thermal: bool, contact: bool, update: tuple | None) -> list[str]:
    matrix = [f"{{}}{a}{b}" for a in range(dim) for b in range(dim)]
    return [
        *_axes(dim, ok=False),
        _zeros([f"vp{c}" for c in AXES[:dim]] + [f"dv{c}" for c in AXES[:dim]]),
        _zeros([m.format("b") for m in matrix]),
        _zeros([m.format("l") for m in matrix]),
        *([_zeros(["dT", "tg", "reach"] + [f"tq{c}" for c in AXES[:dim]]), "kp = conductivity[p]"] if thermal else []),
        *_field_shift(contact),
        f"wdx = {_each('wx[{a}] * (({a} - fx) * h0)', 3)}   # (wx has 3 entries for every support)",
        *_stencil(dim, _g2p_gather(dim, thermal), gradients=True, contact=contact,
                  row_start=_g2p_row_start(dim), row_end=_g2p_row_end(dim)),
        "if mode != KINEMATICS:",
        "    if blend:",
        *_indent(_each_line("v[p, {a}] = flip * (v[p, {a}] + dv{c}) + (1.0 - flip) * vp{c}", dim), 2),
        "    else:",
        f"        {_each('v[p, {a}]', dim)} = {_each('vp{c}', dim)}",
        "    if affine:",
        *_indent(_tensor("C[p, {a}, {b}] = b{a}{b} * d_inv{b}", dim), 2),
        *_g2p_remap(dim, thermal, contact),
        *(["if mode == KINEMATICS:   # q_p = -k_p sum grad w T_I^{t+dt}",
           *_indent(_each_line("heat_flux[p, {a}] = -kp * tq{c}", dim), 1)] if thermal else []),
        "if mode == USL:",
        *_indent(_each_line("x[p, {a}] += dt * vp{c}", dim), 1),
        "else:",
        *_indent(_each_line("x[p, {a}] += dt * rate[p, {a}]", dim), 1),
        "if mls:   # L_p = B_p D_p^-1: C_p itself after a USL gather",
        *_indent(_tensor("l{a}{b} = b{a}{b} * d_inv{b}", dim), 1),
        "if not l_is_c:   # (else L_p is left to the particles' deferred update, solver/step/fused.py)",
        *_indent(_tensor("L[p, {a}, {b}] = l{a}{b}", dim), 1),
        *_stress_update(update),
        *_deformation_gradient(dim),
        f"J = {_determinant(list(range(dim)), list(range(dim)))}",
        "volume[p] = J * volume0[p]",
        "if J <= 0.0 and bad[t] < 0:",
        "    bad[t] = p",
    ]


def _g2p(dim: int, thermal: bool, contact: bool, update: tuple | None, contract: bool) -> list[str]:
    return _shell(
        "g2p(variant, x, v, C, mass, L, F, volume, volume0, rate, frame, v_old, v_new, grid_mom,\n"
        "        flip, dt, d_inv, copies_mom, stress, material, bad"
        + (",\n        capacity, T, conductivity, heat_flux, T_change, T_grid, held, remapped, copies_remapped"
           if thermal else "")
        + (",\n        body, field_of_body, n_nodes" if contact else "") + ")",
        "USL: v_p (PIC/FLIP blend), C_p = B_p D_p^-1, x_p += dt v_pic, and L_p, F_p, V_p\n"
        "    from v_new. REMAP: v_p and C_p only, v_pic into `rate`, and the new momentum\n"
        "    m w (v_p + C_p (x_I - x_p)) added to grid_mom (zeroed by the caller). KINEMATICS:\n"
        "    L_p, F_p, V_p from v_new (the remapped velocity), then x_p += dt rate_p.\n"
        "    bad[t]: first particle of block t whose J = det F is not positive.\n\n"
        "    variant: (support, mode, affine, blend, mls, l_is_c, updates) constants; frame: (lower, h,\n"
        "    inv_h, cells, strides, offset); d_inv: D_p^-1 per axis (APIC, MLS). `l_is_c` (MLS, USL): L_p,\n"
        "    which is C_p, is not written. `updates` (USL, KINEMATICS; where the module has a material's\n"
        "    update lines): `stress` is updated from L_p with the parameters `material`."
        + ("\n\n    Conduction (MUSL): REMAP also T_p += sum w T_change (T~_I - T_I) (T_p = sum w T_grid,\n"
           "    T~_I then, where the stencil reaches a node `held` marks: thermal_kernels.\n"
           "    takes_grid_temperature) and sum w m c T_p into `remapped` (zeroed here); KINEMATICS\n"
           "    also q_p = -k_p sum grad w T_grid, T_grid then being the remapped T_I^{t+dt}." if thermal else "")
        + ("\n\n    Contact (a field per body): every node is node + field_of_body[body[p]] * n_nodes."
           if contact else ""),
        ["support, mode_, affine_, blend_, mls_, l_is_c_, updates_ = variant",
         *_parameters(update),
         *_frame(dim),
         f"{_each('d_inv{a}', dim)} = {_each('d_inv[{a}]', dim)}"],
        ["S, affine, blend, mls = support.ndim - 1, affine_.ndim == 2, blend_.ndim == 2, mls_.ndim == 2"
         "   # compile-time constants",
         "mode, l_is_c, updates = mode_.ndim - 1, l_is_c_.ndim == 2, updates_.ndim == 2",
         "gp = own(t, grid_mom, copies_mom) if mode == REMAP else grid_mom",
         *(["tr = own_zeroed(t, remapped, copies_remapped) if mode == REMAP else remapped"] if thermal else [])],
        _g2p_particle(dim, thermal, contact, update),
        ["if remaps:", "    _reduce_mass_momentum(DIMS, remapped, grid_mom, copies_remapped, copies_mom)"]
        if thermal else
        ["if remaps and copies_mom.shape[0] > 0:", "    add_node_copies(grid_mom, copies_mom)"], contract,
        threads="copies_mom.shape[0] + 1", prepare=["remaps = variant[1].ndim - 1 == REMAP   # (mode_)"])


# -- MLS's USL pass, vectorised -------------------------------------------------------

def _flat(name: str, width: int, index: int | str) -> str:
    """Entry `index` of particle or node `name`'s row in a flat array of rows of `width`."""
    return f"{width} * {name} + {index}"


def _g2p_mls_gather(dim: int) -> list[str]:
    """The gather of `_g2p_particle` for MLS under USL with quadratic B-splines, every node written
    out (no loop over a tuple's entries, which LLVM cannot vectorise): v_p, and B_p's entries
    summed along x first (the rows' sums in `_g2p_row_end`'s order, the same bits). The first
    node as `_axis` finds it, inline: with `_axis`'s test of the grid's bounds (the P2G before
    made it), or with the index returned by a function, LLVM leaves the loop scalar."""
    lines = [line for a, c in enumerate(AXES[:dim]) for line in (   # `_axis` for a particle inside the grid
        f"at{c} = (x[{_flat('p', dim, a)}] - lower{a}) * inv_h{a}",
        f"i{c} = min(max(int(at{c} - 0.5), 0), cells{a} - 2)",
        f"f{c} = at{c} - i{c}", f"w{c} = _quadratic(f{c})")]
    lines += [f"wdx = {_each('wx[{a}] * (({a} - fx) * h0)', 3)}",
              _zeros([f"vp{c}" for c in AXES[:dim]] + [f"b{a}{b}" for a in range(dim) for b in range(dim)])]
    for row in np.ndindex(*(3,) * (dim - 1)):   # (j) or (k, j): the outer axis outermost, as `_stencil` nests them
        index = dict(zip(LOOPS[dim - 1:0:-1], row))
        wo = " * ".join(f"w{AXES[a]}[{index[LOOPS[a]]}]" for a in range(1, dim))
        start = " + ".join(f"(i{AXES[a]} + {index[LOOPS[a]]}) * stride{a}" for a in range(1, dim))
        lines += [*[f"d{AXES[a]} = ({index[LOOPS[a]]} - f{AXES[a]}) * h{a}" for a in range(1, dim)],
                  f"row = {start} - offset + ix", f"wo = {wo}", _zeros([f"{n}{c}" for n in "st" for c in AXES[:dim]])]
        for i in range(3):
            node = _flat(f"(row + {i})", dim, "{a}")
            lines += [f"{_each('v{c}', dim)} = {_each(f'v_new[{node}]', dim)}",
                      *_each_line(f"s{{c}} += wx[{i}] * v{{c}}", dim), *_each_line(f"t{{c}} += wdx[{i}] * v{{c}}", dim)]
        lines += [*_each_line("vp{c} += wo * s{c}", dim), *[f"b{a}0 += wo * t{AXES[a]}" for a in range(dim)],
                  *[f"b{a}{b} += (wo * d{AXES[b]}) * s{AXES[a]}" for a in range(dim) for b in range(1, dim)]]
    return lines + [*_each_line(f"v[{_flat('p', dim, '{a}')}] = vp{{c}}", dim),
                    *[f"C[{_flat('p', dim * dim, dim * a + b)}] = b{a}{b} * d_inv{b}"
                      for a in range(dim) for b in range(dim)]]


def _g2p_mls_update(dim: int) -> list[str]:
    """x_p += dt v_p, F_p <- (I + dt L_p) F_p with L_p = C_p, V_p = det F_p V0_p, as
    `_g2p_particle` does them (the same bits); a J <= 0 is counted (`_g2p_mls`)."""
    return [*_each_line(f"x[{_flat('p', dim, '{a}')}] += dt * vp{{c}}", dim),
            *_tensor("l{a}{b} = b{a}{b} * d_inv{b}", dim),
            *_flat_deformation(dim)]


def _flat_deformation(dim: int) -> list[str]:
    """F_p <- (I + dt L_p) F_p and V_p = det F_p V0_p on the flat F, as `_deformation_gradient` and
    `_g2p_particle` form them (the same bits); a J <= 0 is counted in `inverted`."""
    entry = [(a, b) for a in range(dim) for b in range(dim)]
    return [*[f"f{a}{b} = F[{_flat('p', dim * dim, dim * a + b)}]" for a, b in entry],
            *[f"n{a}{b} = f{a}{b} + " + " + ".join(f"dt * l{a}{c} * f{c}{b}" for c in range(dim)) for a, b in entry],
            *[f"F[{_flat('p', dim * dim, dim * a + b)}] = n{a}{b}" for a, b in entry],
            f"J = {_determinant(list(range(dim)), list(range(dim)))}",
            "volume[p] = J * volume0[p]",
            "inverted += J <= 0.0"]


def _flat_determinant(dim: int) -> str:
    """det F_p read from the flat F, expanded as `_determinant` expands the new F (the same J)."""
    text = _determinant(list(range(dim)), list(range(dim)))
    return re.sub(r"n(\d)(\d)", lambda m: f"F[{_flat('p', dim * dim, dim * int(m[1]) + int(m[2]))}]", text)


def _g2p_mls(dim: int, contract: bool) -> list[str]:
    """`g2p` for MLS under USL with C_p as L_p (`l_is_c`), quadratic B-splines and no stress
    update, in a loop LLVM vectorises (the nodes gathered for 8 particles at a time with
    AVX-512; `git show 63f7e3a^:docs/benchmarks.md`, "Speed, eighteenth part"). What keeps `g2p` scalar and is
    different here: the arrays are flat views (the strides of (n, dim) arrays are read at run
    time); the loop counts from 0 from a start known to be non-negative (from lo, or
    with np.uint64 indices, LLVM "cannot identify array bounds"); the first node is found inline
    (`_g2p_mls_gather`); and a J <= 0 is counted, its particle looked for after the loop (a
    conditional store to bad[t] keeps a loop scalar)."""
    return _blocked(
        "g2p_mls(x, v, C, F, v_new, volume, volume0, lower, h, inv_h, cells, strides, offset, d_inv, dt,\n"
        "            threads, bad)",
        "USL with MLS: v_p, C_p = B_p D_p^-1, x_p += dt v_p, F_p and V_p, as `g2p` with l_is_c\n"
        "    (the same bits), on flat views: x, v and the nodes' v_new dim entries a row, C and F dim^2.\n"
        "    bad[t]: first particle of block t whose J = det F is not positive.",
        _flat_frame(dim),
        ["start, inverted = max(lo, 0), 0",
         "for k in range(hi - start):",
         "    p = start + k",
         *_indent(_g2p_mls_gather(dim) + _g2p_mls_update(dim), 1),
         *_inverted_particle(dim)], [], contract, threads=None, particles="volume.shape[0]")


def _inverted_particle(dim: int) -> list[str]:
    """bad[t] after a vectorised loop that counted the particles whose J <= 0 (`inverted`): the
    first of them, its J formed as the loop formed it (were it not found, the block would still
    fail: bad[t] is its start)."""
    return ["bad[t] = -1",
            "if inverted:   # (rare)",
            "    bad[t] = start",
            "    for p in range(start, hi):",
            f"        if {_flat_determinant(dim)} <= 0.0:",
            "            bad[t] = p",
            "            break"]


# -- MUSL's kinematics pass, vectorised ----------------------------------------------------

def _g2p_kinematics_axes(dim: int) -> list[str]:
    """`_axis` for a particle inside the grid, inline (LLVM vectorises it): the first node, f{c}, and
    the weights and gradients the kinematics pass reads, for the compile-time support S (2: linear
    hats, 3: quadratic B-splines), with `_axis`'s expressions (the same bits)."""
    lines = []
    for a, c in enumerate(AXES[:dim]):
        lines += [f"at{c} = (x[{_flat('p', dim, a)}] - lower{a}) * inv_h{a}",
                  "if S == 2:",
                  f"    i{c} = min(int(at{c}), cells{a} - 1)",
                  f"    f{c} = at{c} - i{c}",
                  f"    w{c}0, w{c}1, w{c}2 = 1.0 - f{c}, f{c}, 0.0",
                  f"    g{c}0, g{c}1, g{c}2 = -inv_h{a}, inv_h{a}, 0.0",
                  "else:",
                  f"    i{c} = min(max(int(at{c} - 0.5), 0), cells{a} - 2)",
                  f"    f{c} = at{c} - i{c}",
                  f"    w{c}0, w{c}1, w{c}2 = _quadratic(f{c})",
                  f"    g{c}0, g{c}1, g{c}2 = (-(1.5 - f{c}) * inv_h{a}, -2.0 * (f{c} - 1.0) * inv_h{a},"
                  f" (f{c} - 0.5) * inv_h{a})"]
    return lines


def _g2p_kinematics_gather(dim: int) -> list[str]:
    """L_p = sum v_I grad w_I as `_g2p_gather` and `_g2p_row_end` sum it in the KINEMATICS pass
    (not MLS): along x first (s{c}, u{c}), then the row's outer factor; every node written out, the
    third of a row under `S == 3` (a compile-time constant)."""
    lines = [_zeros([f"l{a}{b}" for a in range(dim) for b in range(dim)])]
    for row in np.ndindex(*(3,) * (dim - 1)):   # (j) or (k, j): the outer axis outermost, as `_stencil` nests them
        index = dict(zip(LOOPS[dim - 1:0:-1], row))
        guard = any(index[LOOPS[a]] == 2 for a in range(1, dim))
        wo = " * ".join(f"w{AXES[a]}{index[LOOPS[a]]}" for a in range(1, dim))
        go = {b: " * ".join(f"{'g' if a == b else 'w'}{AXES[a]}{index[LOOPS[a]]}" for a in range(1, dim))
              for b in range(1, dim)}
        start = " + ".join(f"(i{AXES[a]} + {index[LOOPS[a]]}) * stride{a}" for a in range(1, dim))
        body = [f"row = {start} - offset + ix", _zeros([f"{n}{c}" for n in "su" for c in AXES[:dim]])]
        for i in range(3):
            node = _flat(f"(row + {i})", dim, "{a}")
            gather = [f"{_each('v{c}', dim)} = {_each(f'v_new[{node}]', dim)}",
                      *_each_line(f"s{{c}} += wx{i} * v{{c}}", dim), *_each_line(f"u{{c}} += gx{i} * v{{c}}", dim)]
            body += ["if S == 3:", *_indent(gather, 1)] if i == 2 else gather
        body += [*[f"l{a}0 += {wo} * u{AXES[a]}" for a in range(dim)],
                 *[f"l{a}{b} += {go[b]} * s{AXES[a]}" for a in range(dim) for b in range(1, dim)]]
        lines += ["if S == 3:", *_indent(body, 1)] if guard else body
    return lines


def _g2p_kinematics_update(dim: int) -> list[str]:
    """x_p += dt v_pic, L_p written, F_p and V_p, as `_g2p_particle` does them in the KINEMATICS
    pass (the same bits); a J <= 0 is counted."""
    return [*_each_line(f"x[{_flat('p', dim, '{a}')}] += dt * rate[{_flat('p', dim, '{a}')}]", dim),
            *[f"L[{_flat('p', dim * dim, dim * a + b)}] = l{a}{b}" for a in range(dim) for b in range(dim)],
            *_flat_deformation(dim)]


def _g2p_kinematics(dim: int, contract: bool) -> list[str]:
    """`g2p`'s KINEMATICS pass (MUSL, not MLS: L_p from grad w) without a stress update, in a loop
    LLVM vectorises, written as `_g2p_mls` is: flat views, the first node inline, a J <= 0 counted and
    looked for after the loop. The same bits as `g2p`. A material's update lines stay out: in the
    loop, their read-modify-write of 5 of a particle's 9 stress entries became AVX-512 gathers and
    scatters, and the pass ran twice as slow as `g2p` (the material's own pass runs after it:
    solver/step/fused.py `updates_stress`)."""
    return _blocked(
        "g2p_kinematics(support, x, rate, L, F, v_new, volume, volume0, lower, h, inv_h, cells, strides, offset,\n"
        "                   dt, threads, bad)",
        "MUSL's KINEMATICS pass as `g2p` runs it without MLS and without `updates` (the same bits),\n"
        "    on flat views: x, rate and the nodes' v_new dim entries a row, L and F dim^2. support: the\n"
        "    compile-time constant S (2: linear hats, 3: quadratic B-splines) as `g2p`'s variant has it.\n"
        "    bad[t]: first particle of block t whose J = det F is not positive.",
        _flat_frame(dim)[:-1],   # (no D_p^-1)
        ["S = support.ndim - 1   # a compile-time constant",
         "start, inverted = max(lo, 0), 0",
         "for k in range(hi - start):",
         "    p = start + k",
         *_indent(_g2p_kinematics_axes(dim) + _g2p_kinematics_gather(dim) + _g2p_kinematics_update(dim), 1),
         *_inverted_particle(dim)], [], contract, threads=None, particles="volume.shape[0]")


# -- MLS with a node's values in four lanes: 3D's P2G and G2P (2D's P2G scatter takes the stencil) --

def _lanes_stencil(dim: int) -> list[str]:
    """The stencil of MLS's folded P2G with a node's (m, mv_x, mv_y, mv_z or 0) added as one
    float64x4 (solver/lanes.py) into the thread's (n, 4) rows `gl`: the node's m and
    r{c} + mc{c}0 dx (`_p2g_node`) are lanes base + dx column, the mass lane's column entry 0
    (m + 0 dx is m), so that every lane does `p2g`'s operations on its component."""
    pad = ", 0.0" * (3 - dim)
    return [f"column = lanes_of(0.0, {_each('mc{a}0', dim)}{pad})",
            *_stencil(dim, [f"w = wx[i] * {_outer(dim)}", "dx = (i - fx) * h0",
                            "add_to_row(gl, node, w, axpy(dx, column, base))"], gradients=False, contact=False,
                      row_start=[*_momentum_row(dim), f"base = lanes_of(m, {_each('r{c}', dim)}{pad})"])]


def _p2g_lanes(stress: tuple | None, contract: bool) -> list[str]:
    return _shell(
        "p2g_lanes(variant, x, v, C, mass, volume, stress, F, L, volume0, material, acc, frame, d_inv,\n"
        "        grid_mass, grid_mom, lanes, bad, dt)",
        "`p2g` for MLS's folded P2G in 3D (quadratic B-splines), each thread adding a node's\n"
        "    (m, mv_x, mv_y, mv_z) as one vector into its rows of `lanes` (threads, n, 4; zeroed here),\n"
        "    which are then summed into grid_mass and grid_mom in thread order: the same bits as `p2g`.\n\n"
        "    variant: `p2g`'s, with affine, mls and fold set.",
        ["support, affine_, loaded_, mls_, fold_, inline_ = variant",
         *_parameters(stress),
         *_frame(3),
         "d_inv0, d_inv1, d_inv2 = d_inv[0], d_inv[1], d_inv[2]",
         "shared_acc = acc.shape[0] == 1"],
        ["S, affine, loaded, mls = support.ndim - 1, True, loaded_.ndim == 2, True   # compile-time constants",
         "fold, inline = True, inline_.ndim == 2",
         "gl = lanes[t]",
         "gl[:, :] = 0.0   # (by the thread that adds into them)"],
        _p2g_particle(3, False, False, stress, lanes=True),
        ["unpack_mass_momentum(grid_mass, grid_mom, lanes)"], contract, threads="lanes.shape[0]")


def _g2p_lanes(contract: bool) -> list[str]:
    """MLS's USL pass in 3D (`g2p` with quadratic B-splines, mls, l_is_c, no blend or update),
    each node's velocity gathered as one float64x4: s and t (`_g2p_gather`), v_p and B_p's
    columns b{a}0, b{a}1, b{a}2 (`_g2p_row_end`) are vectors with a lane per component."""
    zero = "lanes_of(0.0, 0.0, 0.0, 0.0)"
    return _shell(
        "g2p_lanes(x, v, C, F, volume, volume0, frame, v_new, v_lanes, dt, d_inv, threads, bad)",
        "`g2p`'s USL pass for MLS in 3D: v_p, C_p = B_p D_p^-1, x_p; F_p and V_p from L_p = C_p (not\n"
        "    written: solver/step/fused.py defers it), the nodes' velocities read as (v_x, v_y, v_z, 0)\n"
        "    rows of v_lanes (n, 4; packed here from v_new). The same bits as `g2p`.",
        [*_frame(3), "d_inv0, d_inv1, d_inv2 = d_inv[0], d_inv[1], d_inv[2]"],
        ["S = 3   # quadratic B-splines"],
        [*_axes(3, ok=False),
         f"vp = b0 = b1 = b2 = {zero}   # v_p and B_p's columns, a lane per component",
         f"wdx = {_each('wx[{a}] * (({a} - fx) * h0)', 3)}",
         *_stencil(3, ["v_node = load_row(v_lanes, node)", "s = axpy(wx[i], v_node, s)",
                       "tw = axpy(wdx[i], v_node, tw)"], gradients=False, contact=False,
                   row_start=[f"s = tw = {zero}"],
                   row_end=["vp = axpy(wo, s, vp)", "b0 = axpy(wo, tw, b0)", "b1 = axpy(wo * dy, s, b1)",
                            "b2 = axpy(wo * dz, s, b2)"]),
         "vpx, vpy, vpz, _ = split(vp)",
         *[f"b0{b}, b1{b}, b2{b}, _ = split(b{b})" for b in range(3)],
         "v[p, 0], v[p, 1], v[p, 2] = vpx, vpy, vpz",
         *_tensor("C[p, {a}, {b}] = b{a}{b} * d_inv{b}", 3),
         *_each_line("x[p, {a}] += dt * vp{c}", 3),
         *_tensor("l{a}{b} = b{a}{b} * d_inv{b}", 3),
         *_deformation_gradient(3),
         f"J = {_determinant([0, 1, 2], [0, 1, 2])}",
         "volume[p] = J * volume0[p]",
         "if J <= 0.0 and bad[t] < 0:",
         "    bad[t] = p"],
        [], contract, threads=None, prepare=["pack_velocity(v_new, v_lanes)"])


# -- the generated module ------------------------------------------------------------

def source(dim: int, thermal: bool = False, contact: bool = False, stress: tuple | None = None,
           update: tuple | None = None, contract: bool | None = None) -> str:
    """The text of the module of the fused kernels for `dim` (2 or 3) dimensions; with
    `thermal`, the kernels that carry conduction too, with `contact` those that step a
    velocity field per body (a scene without them never loads those: its module's text, and
    so its kernels, are those of a template without heat or contact); with `stress`, a
    material's (name, lines, number of parameters), a P2G that can form sigma_p from F_p
    (`_stress_of_particle`); with `update`, a material's (name, lines, number of parameters), a G2P
    that can update the stress from L_p (`_stress_update`); with `contract` (by default what
    the environment asks for: `contracts`) compiled with FMA contraction."""
    if contract is None:
        contract = contracts()
    if thermal and contact:
        raise ValueError("conduction with contact fields runs on the general backend (solver/fused_scope.py)")
    header = (HEADER.format(dim=dim) + ("\nimport math" if stress else "") + (THERMAL_IMPORTS if thermal else "")
              + ("\nfrom solver.fused import _reduce_with" if contact else ""))
    # the passes vectorised across particles: 2D only (in 3D MLS's G2P measured slower, its P2G and the
    # kinematics pass no faster: docs/benchmarks.md); 3D's MLS vectorises within a node instead
    mls = dim == 2 and not (thermal or contact)
    header += MLS_IMPORTS if mls else ""
    # MLS in 3D, and 2D's P2G scatter: a node's values in four lanes (solver/lanes.py)
    lanes = not (thermal or contact)
    header += LANES_IMPORTS.format(operations="contracted" if contract else "exact") if lanes else ""
    header += f"\n\nDIMS = (0,) * {dim}   # the dimension as a compile-time constant (solver/kernels.py axes)"
    return "\n".join([header, *_p2g(dim, thermal, contact, stress, contract),
                      *_g2p(dim, thermal, contact, update, contract),
                      *(_p2g_mls(dim, stress, contract) + _p2g_mls(dim, stress, contract, lanes=True)
                        + _g2p_mls(dim, contract) + _g2p_kinematics(dim, contract) if mls else []),
                      *(_p2g_lanes(stress, contract) + _g2p_lanes(contract) if lanes and dim == 3 else [])]) + "\n"


def _stem(dim: int, thermal: bool, contact: bool, stress: tuple | None, update: tuple | None = None) -> str:
    return (f"fused_{dim}d" + ("_thermal" if thermal else "") + ("_contact" if contact else "")
            + (f"_{stress[0]}" if stress else "") + (f"_{update[0]}" if update else ""))


def write(dim: int, thermal: bool = False, contact: bool = False, stress: tuple | None = None,
          update: tuple | None = None, contract: bool | None = None) -> Path:
    """The generated file for `dim`, (re)written only when its text changed (solver/generated.py)."""
    return generated.write("fused", _stem(dim, thermal, contact, stress, update),
                           source(dim, thermal, contact, stress, update, contract))


def load(dim: int, thermal: bool = False, contact: bool = False, stress: tuple | None = None,
         update: tuple | None = None, contract: bool | None = None):
    """The module of the fused kernels for `dim` dimensions (attributes p2g, g2p)."""
    return generated.load("fused", _stem(dim, thermal, contact, stress, update),
                          source(dim, thermal, contact, stress, update, contract))
