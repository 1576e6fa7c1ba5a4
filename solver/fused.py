"""The update-Lagrangian step fused for the common case, on every thread.

The general step (solver/stepper.py) stores each particle's stencil (node
numbers, weights, gradients) and runs one kernel per phase, so that any shape
function, APIC, axisymmetry and rigid bodies plug in. For the scenes most runs
are (linear hat functions or quadratic B-splines; USL or MUSL; PIC, FLIP or APIC;
no rigid body, no hoop terms) that generality costs memory traffic: the stencil
is written once and read three times a step. Here the weights are recomputed
where they are needed, from the same formulas in the same order, so a fused
step gives the general step's answer to round-off (tests/unit/test_fused.py):

    USL:   p2g -> grid update -> g2p, mode USL (v, C, x, L, F, V) -> material
    MUSL:  p2g -> grid update -> g2p, mode REMAP (v, C; momentum back to the grid)
           -> nodal velocity -> g2p, mode KINEMATICS (L, F, V from the remapped
           velocity; x) -> material

`kernels(dim)` gives the module with the two kernels, `p2g` and `g2p` (in 2D also
`g2p_mls` and `p2g_mls`, MLS's USL pass and folded P2G vectorised, and `g2p_kinematics`, MUSL's
KINEMATICS pass vectorised), for a dimension: they are written out from one
template (solver/fused_template.py)
into a generated, cached source file. This module keeps what every dimension
shares: which scenes they serve (`supports`), the weights along one axis
(`_axis`), the constants below, and APIC's D_p^-1 from the shape function
(`inverse_d`).

Each kernel runs one contiguous block of particles per thread; P2G scatters
into per-thread copies of the nodal arrays, summed afterwards (solver/threads.py).

What a kernel does (the support S = 2 for linear, 3 for quadratic B-splines; the
G2P mode; APIC or not; a FLIP blend or not; a body force or not) reaches it as
the number of dimensions of small empty arrays (`constant`), passed in one tuple
(`variant`): numba compiles one specialisation per array type, so inside the
threads' loops these are compile-time constants and the branches of the other
variants fold away. Plain arguments would be runtime values there (numba passes
what a prange loop uses to the threads' function as arguments; measured, runtime
flags made P2G 20 % slower), and an empty tuple, whose length would say the same,
cannot be passed in. The grid's frame (lower, h, inv_h, cells, strides, offset)
comes as one tuple too; both are unpacked before the threads' loop. The particle
and nodal arrays stay separate arguments: numba types a tuple argument slower than
plain arrays at each call (measured: 0.45 us more per call with every array in a
tuple, 0.18 us with the constants and the frame only, against 6 us for the whole
call on a few hundred particles).
"""
from __future__ import annotations

import functools

import numpy as np
from solver.jit import njit, prange

from solver import shape
from solver.shape.kernels import linear, quadratic_bspline
# the generated kernels' name for the quadratic B-spline's grid-end allowance
from solver.shape.kernels.quadratic_bspline import TOUCH as _TOUCH  # noqa: F401
# which scenes the fused kernels run: decided without numba (the run-time estimates read it too)
from solver.fused_scope import FUSED_SHAPES, supports  # noqa: F401
from solver.threads import add_copies


USL, REMAP, KINEMATICS = 0, 1, 2   # what a g2p kernel does, see the module docstring


def kernels(dim: int, thermal: bool = False, contact: bool = False, stress: tuple | None = None,
            update: tuple | None = None):
    """The module of the fused kernels for `dim` dimensions: `p2g` and `g2p`
    (generated from solver/fused_template.py, see there); with `thermal` the kernels that
    carry heat conduction as well, with `contact` those of a velocity field per body, with
    `stress` (a material's name, lines and number of parameters) a P2G that can form the
    stress from F_p, with `update` (the same) a G2P that can update the stress from L_p
    (separate modules: scenes without them keep theirs); compiled with FMA contraction
    unless MPM_FMA=0 (fused_template.contracts)."""
    from solver import fused_template
    return _kernels(dim, thermal, contact, stress, update, fused_template.contracts())


@functools.cache
def _kernels(dim: int, thermal: bool, contact: bool, stress: tuple | None, update: tuple | None, contract: bool):
    """`kernels`, once per combination: a process that changes MPM_FMA gets the other module."""
    from solver import fused_template
    return fused_template.load(dim, thermal, contact, stress, update, contract)


_CONSTANTS = [np.empty((0,) * n) for n in range(1, 5)]


def constant(value: int) -> np.ndarray:
    """An empty array of value + 1 dimensions: `value` as a compile-time constant
    (read back as `array.ndim - 1`, see the module docstring)."""
    return _CONSTANTS[int(value)]


def support_of(shape_function: str) -> np.ndarray:
    return constant(shape.REGISTRY[shape_function].support)


def inverse_d(apic_d: float, inv_h: np.ndarray) -> np.ndarray:
    """APIC's D_p^-1 per axis for a shape function whose D_p is apic_d h^2 (quadratic
    B-splines: h^2/4): (1 / apic_d) / h^2, computed as (1 / apic_d) inv_h inv_h."""
    return (1.0 / apic_d) * inv_h * inv_h


# -- weights along one axis ------------------------------------------------------

# The quadratic B-spline's 1D weights (its module's formula) compiled once, never contracted:
# the contracted kernels call it too, and a callee inherits its first caller's flags but is
# cached once per signature, so it says its own.
_quadratic = njit(cache=True, fastmath=False)(quadratic_bspline.weights_1d.py_func)


# fastmath=False like the functions it calls (solver/shape/kernels/quadratic_bspline.py says
# why). (inline="always" would give each kernel its own copy, but made the kernels' compile
# several times slower.)
@njit(cache=True, fastmath=False)
def _axis(S, x, lower, inv_h, cells):
    """First node i, position in cells from it f, 1D weights and derivatives (times inv_h) of a
    position along one axis, from the shape modules' own 1D functions (solver/shape/kernels/
    linear.py, quadratic_bspline.py); `ok` is False outside the grid (or NaN), with i = 0.
    Node i + j lies at (j - f) h from the particle."""
    s = (x - lower) * inv_h
    if S == 2:
        ok = linear.inside(s, cells)
        i = linear.first_node(s, cells) if ok else 0
        f = s - i
        (w0, w1), (g0, g1) = linear.weights_1d(f), linear.gradients_1d(inv_h)
        return ok, i, f, (w0, w1, 0.0), (g0, g1, 0.0)
    ok = quadratic_bspline.inside(s, cells)
    i = quadratic_bspline.first_node(s, cells) if ok else 0
    f = s - i
    return ok, i, f, _quadratic(f), quadratic_bspline.gradients_1d(f, inv_h)


# twin=True: a run on one thread calls the copies' serial twin through them (solver/jit.py).
@njit(twin=True, cache=True)
def _reduce(dims, grid_mass, grid_mom, grid_force, copies_mass, copies_mom, copies_force):
    if copies_mass.shape[0] > 0:
        add_copies(dims, grid_mass, grid_mom, grid_force, copies_mass, copies_mom, copies_force)



@njit(twin=True, cache=True)
def _reduce_mass_momentum(dims, grid_mass, grid_mom, copies_mass, copies_mom):
    """`_reduce` of a P2G that folded the force into the momentum (no force copies to add); also
    the REMAP pass's with conduction, its remapped m c T in the place of the mass."""
    if copies_mass.shape[0] > 0:
        _add_mass_momentum_copies(dims, grid_mass, grid_mom, copies_mass, copies_mom)


@njit(cache=True, inline="always")
def _add_mass_momentum_at(grid_mass, grid_mom, copies_mass, copies_mom, i, dim):
    for t in range(copies_mass.shape[0]):
        grid_mass[i] += copies_mass[t, i]
        for a in range(dim):
            grid_mom[i, a] += copies_mom[t, i, a]


@njit(parallel=True, cache=True)
def _add_mass_momentum_copies(dims, grid_mass, grid_mom, copies_mass, copies_mom):
    """As solver/threads.py's add_copies without the force: one parallel loop over the nodes
    (two, one per array, were not faster), the component loop unrolled (`dims`)."""
    for i in prange(grid_mom.shape[0]):
        _add_mass_momentum_at(grid_mass, grid_mom, copies_mass, copies_mom, i, len(dims))


@njit(twin=True, cache=True)
def _reduce_with(grid_mass, grid_mom, grid_force, extra, more, copies_mass, copies_mom, copies_force, copies_extra,
                 copies_more):
    """`_reduce` of a P2G that scattered two more nodal arrays, (n, k) each (conduction: the heat and
    an empty one; contact: the presence as (n, 1) and the normals' gradient)."""
    if copies_mass.shape[0] > 0:
        _add_copies_with(grid_mass, grid_mom, grid_force, extra, more, copies_mass, copies_mom, copies_force,
                         copies_extra, copies_more)


@njit(parallel=True, cache=True)
def _add_copies_with(grid_mass, grid_mom, grid_force, extra, more, copies_mass, copies_mom, copies_force,
                     copies_extra, copies_more):
    """As solver/threads.py's add_copies with `extra` and `more`: one parallel loop over the nodes for
    all of them, not one each (each loop ends in a wait for the slowest thread); the same sums."""
    n, dim = grid_mom.shape
    for i in prange(n):
        for t in range(copies_mass.shape[0]):
            grid_mass[i] += copies_mass[t, i]
            for a in range(dim):
                grid_mom[i, a] += copies_mom[t, i, a]
                grid_force[i, a] += copies_force[t, i, a]
            for c in range(extra.shape[1]):
                extra[i, c] += copies_extra[t, i, c]
            for c in range(more.shape[1]):
                more[i, c] += copies_more[t, i, c]
