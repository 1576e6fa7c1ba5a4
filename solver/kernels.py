"""Numba kernels of the explicit MPM step, one per phase of the algorithm.

All kernels work on the precomputed stencil of each particle (idx, w, dw: node
index, weight and weight gradient, see solver/shape), so they are the same for
every shape function and every dimension. Arrays are contiguous float64
(int64 for indices); grid vectors are (n_nodes, dim), particle tensors
(n, dim, dim), stresses always 3x3 (plane strain keeps sigma_zz).

Every kernel runs one contiguous block of particles per thread (solver/threads.py).
P2G scatters particle data to nodes, and two particles may share a node: block t
adds into its own copy of the nodal arrays (`own`, block 0 into the grid itself;
the stepper's `ScatterCopies`), summed afterwards, so the block count is the
copies' count plus one. Gathers write only their own particles' rows.

`spec` is a pair of tuples ((0,) * dim, (0,) * nodes_per_particle): numba
compiles one specialisation per tuple type, so the dimension and the stencil
size are compile-time constants and the small inner loops unroll. See
`stencil_spec`.

A parallel kernel is a prange over the blocks that calls a serial kernel for one
block (`_p2g_block`...) with spec's two tuples apart (numba cannot pass a nested
tuple into a parallel loop's body). The serial kernel takes their len(), so they
stay compile-time constants, and allocates its own scratch: numba cannot hoist an
allocation out of a called function and share it between threads, and fresh
arrays ran faster than slices of one scratch array allocated before the prange
(likely: the compiler cannot rule out that a slice aliases what the loop writes)
(measured on one thread: update_kinematics 1.8x slower with slices, 3.9x with the
lengths taken outside the prange as well; P2G 1.5x, G2P 2.2x).

The block loops index particles and nodes with unsigned integers (`range(np.uint64(start),
np.uint64(stop))`, `np.uint64(idx[p, k])`): numba wraps a negative signed index around, a
compare and a select at every access; unsigned ones skip it (docs/internals.md).
"""
from __future__ import annotations

import numpy as np
from solver.jit import njit, prange

from solver.threads import add_copies, add_node_copies, block_bounds, first_of, own


def axes(dim: int) -> tuple:
    """`dim` as a kernel's compile-time constant: a tuple of that length, read as `len(dims)`.
    numba compiles one specialisation per tuple length, so loops over `range(len(dims))`
    unroll as over a literal; one loop over a runtime dim ran the linear elastic update
    2.3-3.5x slower."""
    return (0,) * dim


def stencil_spec(dim: int, nodes_per_particle: int) -> tuple:
    return (axes(dim), (0,) * nodes_per_particle)


def widest_stencil(dim: int) -> int:
    """The most nodes per axis a stencil may have: numba unpacks the tuples a parallel
    region reads, spec's node tuple among them, up to NUMBA_PARFOR_MAX_TUPLE_SIZE (100)
    elements and refuses longer ones (10 per axis in 2D, 4 in 3D)."""
    import numba
    return int(numba.config.PARFOR_MAX_TUPLE_SIZE ** (1.0 / dim) + 1e-9)


_FLAGS = (np.empty((0,)), np.empty((0, 0)))


def flag(value: bool) -> np.ndarray:
    """A boolean as a compile-time constant of a kernel: an empty array of 1 (False) or 2
    (True) dimensions, read as `array.ndim == 2`. numba compiles one specialisation per
    array type, so the branch not taken folds away; a plain bool would be a runtime value
    inside the threads' loop (solver/fused.py measured 20 % on P2G for such flags)."""
    return _FLAGS[int(bool(value))]


def rows_equal(a: np.ndarray, value, block: int = 1 << 16) -> bool:
    """Whether every row of `a` (one a particle) equals `value` (a scalar or one row), compared
    a block of rows at a time: the comparison's temporaries stay small on a large model."""
    return all(np.array_equal(a[s:s + block], np.broadcast_to(value, a[s:s + block].shape))
               for s in range(0, a.shape[0], block))


@njit(parallel=True, cache=True)
def p2g(spec, idx, w, dw, mass, vel, volume, stress, acc, grid_mass, grid_mom, grid_force,
        copies_mass, copies_mom, copies_force):
    """Mass, momentum and force to the grid (Algorithm 1, lines 8-12).

    f_I = sum_p m_p phi_I b_p - V_p sigma_p . grad phi_I. `acc` is the body
    acceleration per particle, or a single row shared by all (gravity only).
    """
    dims, nodes = spec
    blocks = copies_mass.shape[0] + 1
    bounds = block_bounds(w.shape[0], blocks)
    for t in prange(blocks):
        _p2g_block(dims, nodes, bounds[t], bounds[t + 1], idx, w, dw, mass, vel, volume, stress, acc,
                   own(t, grid_mass, copies_mass), own(t, grid_mom, copies_mom), own(t, grid_force, copies_force))
    if blocks > 1:
        add_copies(dims, grid_mass, grid_mom, grid_force, copies_mass, copies_mom, copies_force)


@njit(cache=True)
def _p2g_block(dims, nodes, start, stop, idx, w, dw, mass, vel, volume, stress, acc, grid_mass, grid_mom, grid_force):
    dim, nk = len(dims), len(nodes)
    shared_acc = acc.shape[0] == 1
    vs = np.empty((dim, dim))   # V_p sigma_p, hoisted out of the node loop
    mv = np.empty(dim)
    ma = np.empty(dim)
    for p in range(np.uint64(start), np.uint64(stop)):
        m = mass[p]
        vol = volume[p]
        ap = np.uint64(0) if shared_acc else p
        for a in range(dim):
            mv[a] = m * vel[p, a]
            ma[a] = m * acc[ap, a]
            for b in range(dim):
                vs[a, b] = vol * stress[p, a, b]
        for k in range(nk):
            node = np.uint64(idx[p, k])
            wk = w[p, k]
            grid_mass[node] += wk * m
            for a in range(dim):
                grid_mom[node, a] += wk * mv[a]
                f = wk * ma[a]
                for b in range(dim):
                    f -= vs[a, b] * dw[p, k, b]
                grid_force[node, a] += f


@njit(parallel=True, cache=True)
def p2g_mass_momentum(spec, idx, w, mass, vel, grid_mass, grid_mom, copies_mass, copies_mom):
    """Mass and momentum only (the first transfer of USF)."""
    dims, nodes = spec
    blocks = copies_mass.shape[0] + 1
    bounds = block_bounds(w.shape[0], blocks)
    for t in prange(blocks):
        _mass_momentum_block(dims, nodes, bounds[t], bounds[t + 1], idx, w, mass, vel,
                             own(t, grid_mass, copies_mass), own(t, grid_mom, copies_mom))
    if blocks > 1:
        add_node_copies(grid_mass, copies_mass)
        add_node_copies(grid_mom, copies_mom)


@njit(cache=True)
def _mass_momentum_block(dims, nodes, start, stop, idx, w, mass, vel, grid_mass, grid_mom):
    dim, nk = len(dims), len(nodes)
    for p in range(np.uint64(start), np.uint64(stop)):
        m = mass[p]
        for k in range(nk):
            node = np.uint64(idx[p, k])
            mw = m * w[p, k]
            grid_mass[node] += mw
            for a in range(dim):
                grid_mom[node, a] += mw * vel[p, a]


@njit(parallel=True, cache=True)
def p2g_force(spec, idx, w, dw, mass, volume, stress, acc, grid_force, copies_force):
    """Internal and external nodal forces (USF computes them after the stress update)."""
    dims, nodes = spec
    blocks = copies_force.shape[0] + 1
    bounds = block_bounds(w.shape[0], blocks)
    for t in prange(blocks):
        _force_block(dims, nodes, bounds[t], bounds[t + 1], idx, w, dw, mass, volume, stress, acc,
                     own(t, grid_force, copies_force))
    if blocks > 1:
        add_node_copies(grid_force, copies_force)


@njit(cache=True)
def _force_block(dims, nodes, start, stop, idx, w, dw, mass, volume, stress, acc, grid_force):
    dim, nk = len(dims), len(nodes)
    shared_acc = acc.shape[0] == 1
    for p in range(np.uint64(start), np.uint64(stop)):
        m = mass[p]
        vol = volume[p]
        ap = np.uint64(0) if shared_acc else p
        for k in range(nk):
            node = np.uint64(idx[p, k])
            mw = m * w[p, k]
            for a in range(dim):
                f = mw * acc[ap, a]
                for b in range(dim):
                    f -= vol * stress[p, a, b] * dw[p, k, b]
                grid_force[node, a] += f


# The node loops below run on every thread: each node is its own (the same bits for any
# thread count), and their divisions made the serial loop about 3 % of a 2D MLS step at
# one thread (cProfile) and twice that share at two. Each takes the dimension as a compile-time
# constant (`dims`, `axes`), so that the component loop unrolls and the node loop vectorises:
# integrate_nodes 1.7x in 2D and 1.3x in 3D at one thread, the same divisions.

@njit(cache=True, inline="always")
def _nodal_velocity_at(grid_mass, grid_mom, v, node, dim):
    m = grid_mass[node]
    for a in range(dim):
        v[node, a] = grid_mom[node, a] / m if m > 0.0 else 0.0


@njit(parallel=True, cache=True)
def nodal_velocity(dims, grid_mass, grid_mom, v):
    """v_I = (mv)_I / m_I: a mass-weighted average of particle velocities, bounded
    however small m_I is; 0 on nodes no particle touches."""
    for node in prange(v.shape[0]):
        _nodal_velocity_at(grid_mass, grid_mom, v, node, len(dims))


@njit(cache=True, inline="always")
def _integrate_at(dt, grid_mass, grid_mom, force_then_v, mass_cutoff, v_new, node, dim):
    m = grid_mass[node]
    for a in range(dim):
        f = force_then_v[node, a]
        v = grid_mom[node, a] / m if m > 0.0 else 0.0
        force_then_v[node, a] = v
        v_new[node, a] = v + dt * f / m if m > mass_cutoff else v


@njit(parallel=True, cache=True)
def integrate_nodes(dims, dt, grid_mass, grid_mom, force_then_v, mass_cutoff, v_new):
    """v_I^t = (mv)_I / m_I into the array that held f_I (the grid's v_old but under USF,
    solver/state.py v_old_in_force), and v~_I^{t+dt} = v_I^t + dt f_I / m_I.

    The acceleration f_I / m_I is unbounded on nodes that a particle barely
    touches (review 2.5.3, E24): below `mass_cutoff` it is dropped. This is the
    cut-off of review eq. 2.63 applied to the acceleration rather than the
    velocity, so that a rigid translation stays exact.
    """
    for node in prange(v_new.shape[0]):
        _integrate_at(dt, grid_mass, grid_mom, force_then_v, mass_cutoff, v_new, node, len(dims))


@njit(cache=True)
def apply_dirichlet(bc_node, bc_axis, bc_value, grid_mass, v):
    """Impose prescribed velocity components; returns the work the constraint does,
    sum m_I (v_bar - v_free) v_bar, for the energy balance."""
    work = 0.0
    for i in range(bc_node.shape[0]):
        node = bc_node[i]
        a = bc_axis[i]
        work += grid_mass[node] * (bc_value[i] - v[node, a]) * bc_value[i]
        v[node, a] = bc_value[i]
    return work


@njit(parallel=True, cache=True)
def g2p(spec, idx, w, dt, flip_ratio, v_old, v_new, x, vel, mass, double_map, grid_mom_new, copies_mom):
    """Particle velocity (PIC/FLIP blend, eq. 2.53) and position (eq. 2.54).

    With `double_map` (MUSL) the updated particle momentum is mapped back to the
    grid in the same pass (Algorithm 1, line 20): it uses the old weights too.
    """
    dims, nodes = spec
    blocks = copies_mom.shape[0] + 1
    bounds = block_bounds(w.shape[0], blocks)
    for t in prange(blocks):
        gp = own(t, grid_mom_new, copies_mom) if double_map else grid_mom_new
        _g2p_block(dims, nodes, bounds[t], bounds[t + 1], idx, w, dt, flip_ratio, v_old, v_new, x, vel, mass,
                   double_map, gp)
    if double_map and blocks > 1:
        add_node_copies(grid_mom_new, copies_mom)


@njit(cache=True)
def _g2p_block(dims, nodes, start, stop, idx, w, dt, flip_ratio, v_old, v_new, x, vel, mass, double_map, grid_mom_new):
    dim, nk = len(dims), len(nodes)
    v_pic = np.zeros(dim)
    dv = np.zeros(dim)
    for p in range(np.uint64(start), np.uint64(stop)):
        for a in range(dim):
            v_pic[a] = 0.0
            dv[a] = 0.0
        for k in range(nk):
            node = np.uint64(idx[p, k])
            wk = w[p, k]
            for a in range(dim):
                v_pic[a] += wk * v_new[node, a]
                dv[a] += wk * (v_new[node, a] - v_old[node, a])
        for a in range(dim):
            x[p, a] += dt * v_pic[a]
            vel[p, a] = flip_ratio * (vel[p, a] + dv[a]) + (1.0 - flip_ratio) * v_pic[a]
        if double_map:
            m = mass[p]
            for k in range(nk):
                node = np.uint64(idx[p, k])
                mw = m * w[p, k]
                for a in range(dim):
                    grid_mom_new[node, a] += mw * vel[p, a]


@njit(parallel=True, cache=True)
def update_kinematics(spec, idx, dw, v_grid, dt, L, F, volume, volume0, blocks, reference):
    """The particles' kinematics from the grid velocity, and V = det(F) V0.

    `reference` is `flag(False)` or `flag(True)` (a compile-time constant, see `flag`).
    Update-Lagrangian (False): L_p = sum_I v_I (x) grad phi_I and
    F <- (I + L dt) F (eq. 2.55). Total-Lagrangian (True, dw the reference gradients):
    F_dot = sum_I v_I (x) grad0 phi_I, F <- F + dt F_dot and L = F_dot F^-1
    (Algorithm 3, lines 23-25), so the materials get L either way.

    Returns the index of the first particle whose J = det F is not positive
    (the element has inverted: the run is unstable), or -1.
    """
    dims, nodes = spec
    bounds = block_bounds(idx.shape[0], blocks)
    bad = np.empty(blocks, dtype=np.int64)
    for t in prange(blocks):
        bad[t] = _kinematics_block(dims, nodes, bounds[t], bounds[t + 1], idx, dw, v_grid, dt, L, F, volume, volume0,
                                   reference)
    return first_of(bad)


@njit(cache=True)
def _kinematics_block(dims, nodes, start, stop, idx, dw, v_grid, dt, L, F, volume, volume0, reference):
    dim, nk = len(dims), len(nodes)
    G = np.empty((dim, dim))      # L_p, or F_dot_p in the reference configuration
    work = np.empty((dim, dim))   # F_p before the update, or F_p^-1
    # (the two updates are written out here: as inlined helper functions the
    # total-Lagrangian one ran 1.6x slower, measured on the E6 square)
    bad = -1
    for p in range(np.uint64(start), np.uint64(stop)):
        G[:, :] = 0.0
        for k in range(nk):
            node = np.uint64(idx[p, k])
            for a in range(dim):
                va = v_grid[node, a]
                for b in range(dim):
                    G[a, b] += va * dw[p, k, b]
        if reference.ndim == 2:
            for a in range(dim):
                for b in range(dim):
                    F[p, a, b] += dt * G[a, b]
            J = invert(F[p], work)
            for a in range(dim):
                for b in range(dim):
                    s = 0.0
                    for c in range(dim):
                        s += G[a, c] * work[c, b]
                    L[p, a, b] = s
        else:
            for a in range(dim):
                for b in range(dim):
                    work[a, b] = F[p, a, b]
                    L[p, a, b] = G[a, b]
            for a in range(dim):
                for b in range(dim):
                    s = work[a, b]
                    for c in range(dim):
                        s += dt * G[a, c] * work[c, b]
                    F[p, a, b] = s
            J = determinant(F[p])
        volume[p] = J * volume0[p]
        if J <= 0.0 and bad < 0:
            bad = np.int64(p)
    return bad


@njit(cache=True)
def determinant(A):
    dim = A.shape[0]
    if dim == 1:
        return A[0, 0]
    if dim == 2:
        return A[0, 0] * A[1, 1] - A[0, 1] * A[1, 0]
    return (A[0, 0] * (A[1, 1] * A[2, 2] - A[1, 2] * A[2, 1])
            - A[0, 1] * (A[1, 0] * A[2, 2] - A[1, 2] * A[2, 0])
            + A[0, 2] * (A[1, 0] * A[2, 1] - A[1, 1] * A[2, 0]))


@njit(cache=True)
def invert(A, out):
    """out = A^-1 for a 1x1, 2x2 or 3x3 matrix; returns det A (out is garbage when it is 0)."""
    dim = A.shape[0]
    det = determinant(A)
    r = 1.0 / det if det != 0.0 else 0.0
    if dim == 1:
        out[0, 0] = r
    elif dim == 2:
        out[0, 0] = A[1, 1] * r
        out[0, 1] = -A[0, 1] * r
        out[1, 0] = -A[1, 0] * r
        out[1, 1] = A[0, 0] * r
    else:
        for i in range(3):
            for j in range(3):
                # cofactor of A[j, i]: the cyclic indices avoid the sign bookkeeping
                j1, j2 = (j + 1) % 3, (j + 2) % 3
                i1, i2 = (i + 1) % 3, (i + 2) % 3
                out[i, j] = (A[j1, i1] * A[j2, i2] - A[j1, i2] * A[j2, i1]) * r
    return det


@njit(cache=True)
def kinetic_energy(mass, vel):
    e = 0.0
    n, dim = vel.shape
    for p in range(n):
        s = 0.0
        for a in range(dim):
            s += vel[p, a] * vel[p, a]
        e += 0.5 * mass[p] * s
    return e


@njit(cache=True, inline="always")
def _external_power(mass, acc, vel, shared_acc, dim):
    e = 0.0
    for p in range(vel.shape[0]):
        ap = 0 if shared_acc else p
        s = 0.0
        for a in range(dim):
            s += acc[ap, a] * vel[p, a]
        e += mass[p] * s
    return e


@njit(cache=True)
def external_power(mass, acc, vel):
    """sum_p m_p b_p . v_p, `acc` per particle or one shared row (as in p2g).

    Serial, so the same sum for any thread count; one pass without the temporaries
    of the numpy expression, which took 10 % of a two-thread step. One loop per dimension
    and kind of `acc`, constants in each (the component loop unrolled, no select per
    particle): 1.4-2.1x, the same sum (`git show 63f7e3a^:docs/benchmarks.md`,
    "Speed, twelfth part")."""
    dim, shared = vel.shape[1], acc.shape[0] == 1
    if shared:
        if dim == 2:
            return _external_power(mass, acc, vel, True, 2)
        return _external_power(mass, acc, vel, True, 3) if dim == 3 else _external_power(mass, acc, vel, True, 1)
    if dim == 2:
        return _external_power(mass, acc, vel, False, 2)
    return _external_power(mass, acc, vel, False, 3) if dim == 3 else _external_power(mass, acc, vel, False, 1)


@njit(cache=True)
def max_speed_per_axis(vel):
    n, dim = vel.shape
    out = np.zeros(dim)
    for p in range(n):
        for a in range(dim):
            s = abs(vel[p, a])
            if s > out[a]:
                out[a] = s
    return out


@njit(cache=True)
def first_non_finite(x, vel, stress):
    """Index of the first particle with a non-finite position, velocity or stress, or -1."""
    n, dim = x.shape
    for p in range(n):
        for a in range(dim):
            if not (np.isfinite(x[p, a]) and np.isfinite(vel[p, a])):
                return p
        for a in range(3):
            for b in range(3):
                if not np.isfinite(stress[p, a, b]):
                    return p
    return -1
