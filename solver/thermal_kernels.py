"""Numba kernels of explicit heat conduction ([R] Algorithm 8) on the step's stored
stencil (idx, w, dw at x_p^t), threaded as solver/kernels.py is: scatters add each
particle block into its own copy of the nodal arrays, gathers write their own rows.

The nodal thermal array `heat` is (fields * n_nodes, 3) (contact "friction": a field per
body, node I of field f at f * n_nodes + I): the capacity C_I = sum_p phi_I m_p c_p,
the capacity-weighted temperature sum_p phi_I m_p c_p T_p, and the heat rate
Q_I = sum_p V_p q_p . grad phi_I (+ the boundary terms the hook adds).
"""
from __future__ import annotations

import numpy as np
from solver.jit import njit, prange

from solver import kernels
from solver.threads import add_node_copies, block_bounds, own


@njit(parallel=True, cache=True)
def p2g(spec, idx, w, dw, mass, capacity, T, volume, flux, heat, copies):
    """C_I, (C T)_I and Q_I^int (Algorithm 8, lines 3-7)."""
    dims, nodes = spec
    blocks = copies.shape[0] + 1
    bounds = block_bounds(w.shape[0], blocks)
    for t in prange(blocks):
        _p2g_block(dims, nodes, bounds[t], bounds[t + 1], idx, w, dw, mass, capacity, T, volume, flux,
                   own(t, heat, copies))
    if blocks > 1:
        add_node_copies(heat, copies)


@njit(cache=True)
def _p2g_block(dims, nodes, start, stop, idx, w, dw, mass, capacity, T, volume, flux, heat):
    dim, nk = len(dims), len(nodes)
    for p in range(start, stop):
        mc = mass[p] * capacity[p]
        if mc == 0.0:   # a material that takes no part in conduction
            continue
        mct = mc * T[p]
        vol = volume[p]
        for k in range(nk):
            node = idx[p, k]
            wk = w[p, k]
            q = 0.0
            for a in range(dim):
                q += flux[p, a] * dw[p, k, a]
            heat[node, 0] += wk * mc
            heat[node, 1] += wk * mct
            heat[node, 2] += vol * q


# The two passes every conducting step makes over all nodes (integrate, remapped_temperature)
# are threaded, one block of nodes a thread; with one thread the hook calls the block function
# itself (a parallel region of one thread costs about 1 us a call, 2 % of a small scene's step).
# The other node passes stay serial: a face's nodes are fewer than it costs to wake the
# threads, and the contact's exchanges run on the general backend only.

@njit(parallel=True, cache=True)
def integrate(dt, heat, cutoff, T_old, T_new, T_change, blocks):
    """`integrate_block` over all nodes, one block a thread."""
    bounds = block_bounds(heat.shape[0], blocks)
    for t in prange(blocks):
        integrate_block(bounds[t], bounds[t + 1], dt, heat, cutoff, T_old, T_new, T_change)


@njit(cache=True)
def integrate_block(start, stop, dt, heat, cutoff, T_old, T_new, T_change):
    """T_I^t = (C T)_I / C_I (eq. 5.25) and T~_I^{t+dt} = T_I^t + dt Q_I / C_I (Algorithm 8,
    line 9) where the node has capacity; 0 elsewhere. T_change = T~_I - T_I, which the fused
    REMAP pass reads, formed here by the thread that wrote the node (a pass of its own after
    this one read the other thread's nodes from its cache: 10-40 us a step on 40k nodes)."""
    for i in range(start, stop):
        if heat[i, 0] > cutoff:
            T_old[i] = heat[i, 1] / heat[i, 0]
            T_new[i] = T_old[i] + dt * heat[i, 2] / heat[i, 0]
        else:
            T_old[i] = 0.0
            T_new[i] = 0.0
        T_change[i] = T_new[i] - T_old[i]


@njit(cache=True, inline="always")
def _capacity_at(heat, i, n_nodes, cutoff):
    """C_I of node i: the capacities of its fields (one per body with contact) that hold heat,
    above `cutoff`, summed."""
    capacity = 0.0
    for f in range(heat.shape[0] // n_nodes):
        e = f * n_nodes + i
        if heat[e, 0] > cutoff:
            capacity += heat[e, 0]
    return capacity


@njit(cache=True)
def boundary_heat(node, area, flux, coefficient, ambient, which, n_nodes, heat, cutoff):
    """Q_I += A_I (q* + h (T_amb - T_I^t)) on the faces' nodes that have capacity, with
    T_I^t = (C T)_I / C_I over the node's fields (contact: one per body) that have capacity,
    each field taking its share C_f / C_I of the rate; returns the heat rate that entered (W).
    With one field the share is C / C = 1 exactly: the same bits as a field-free sum."""
    fields = heat.shape[0] // n_nodes
    total = 0.0
    for j in range(node.shape[0]):
        i = node[j]
        capacity = _capacity_at(heat, i, n_nodes, cutoff)
        weighted = 0.0
        for f in range(fields):
            e = f * n_nodes + i
            if heat[e, 0] > cutoff:
                weighted += heat[e, 1]
        if capacity > 0.0:
            c = which[j]
            rate = area[j] * (flux[c] + coefficient[c] * (ambient[c] - weighted / capacity))
            for f in range(fields):
                e = f * n_nodes + i
                if heat[e, 0] > cutoff:
                    heat[e, 2] += rate * (heat[e, 0] / capacity)
            total += rate
    return total


@njit(cache=True)
def hold(node, value, n_nodes, T_grid):
    """Dirichlet nodes: T_I = T* (Algorithm 8, lines 10 and 14), in every field."""
    for f in range(T_grid.shape[0] // n_nodes):
        for j in range(node.shape[0]):
            T_grid[f * n_nodes + node[j]] = value[j]


@njit(cache=True)
def hold_change(node, now, then, n_nodes, T_change):
    """T_change at the Dirichlet nodes: T*(t + dt) - T*(t), the difference `integrate` would
    have formed from the held values."""
    for f in range(T_change.shape[0] // n_nodes):
        for j in range(node.shape[0]):
            T_change[f * n_nodes + node[j]] = then[j] - now[j]


# Contact with a field per body (solver/contact.py): perfect thermal contact. At a node
# where the bodies touch, the fields that hold heat there are one thermal field: each
# takes the capacity-weighted mean sum_f C_f T_f / sum_f C_f, which keeps sum_f C_f T_f,
# so the heat the particles take, sum_I C_I (T~_I - T_I), is unchanged by the exchange.
# Two bodies that stay in contact conduct as the single field conducts them.

@njit(cache=True)
def share_temperature(heat, touching, n_nodes, cutoff, T_grid):
    """At the nodes `touching` marks, the fields with capacity take their C-weighted mean T."""
    fields = heat.shape[0] // n_nodes
    for i in range(n_nodes):
        if not touching[i]:
            continue
        capacity = _capacity_at(heat, i, n_nodes, cutoff)
        weighted = 0.0
        for f in range(fields):
            e = f * n_nodes + i
            if heat[e, 0] > cutoff:
                weighted += heat[e, 0] * T_grid[e]
        if capacity > 0.0:
            mean = weighted / capacity
            for f in range(fields):
                e = f * n_nodes + i
                if heat[e, 0] > cutoff:
                    T_grid[e] = mean


@njit(cache=True)
def deposit_heat(heat, touching, n_nodes, cutoff, added, T_new):
    """T~_I += Q_I / C_I for the heat `added` at the nodes this step (frictional work, J), then
    added = 0. Where the bodies touch (`touching`, empty: nowhere) the node's heat, whichever
    field it was counted in, goes into the common temperature of its fields with capacity;
    elsewhere into its own field. Returns the heat that found no capacity (J)."""
    fields = heat.shape[0] // n_nodes
    lost = 0.0
    for i in range(n_nodes):
        if touching.shape[0] > 0 and touching[i]:
            capacity = _capacity_at(heat, i, n_nodes, cutoff)
            q = 0.0
            for f in range(fields):
                e = f * n_nodes + i
                q += added[e]
                added[e] = 0.0
            if q == 0.0:
                continue
            if capacity > 0.0:
                for f in range(fields):
                    e = f * n_nodes + i
                    if heat[e, 0] > cutoff:
                        T_new[e] += q / capacity
            else:
                lost += q
            continue
        for f in range(fields):
            e = f * n_nodes + i
            if added[e] != 0.0:
                if heat[e, 0] > cutoff:
                    T_new[e] += added[e] / heat[e, 0]
                else:
                    lost += added[e]
                added[e] = 0.0
    return lost


@njit(parallel=True, cache=True)
def g2p_remap(spec, idx, w, T_old, T_new, held, mass, capacity, T, remapped, copies):
    """T_p += sum_I phi_I (T~_I - T_I) (line 12), or T_p = sum_I phi_I T~_I where the particle's
    stencil reaches a held node (`held` 1 there, else 0: `takes_grid_temperature`), then
    sum_p phi_I m_p c_p T_p into `remapped` (line 13, before the division by C_I)."""
    dims, nodes = spec
    blocks = copies.shape[0] + 1
    bounds = block_bounds(w.shape[0], blocks)
    for t in prange(blocks):
        _g2p_remap_block(nodes, bounds[t], bounds[t + 1], idx, w, T_old, T_new, held, mass, capacity, T,
                         own(t, remapped, copies))
    if blocks > 1:
        add_node_copies(remapped, copies)


@njit(cache=True)
def takes_grid_temperature(reach: float, T_p: float, change: float, grid: float) -> float:
    """The particle's new temperature: FLIP, T_p + sum phi_I (T~_I - T_I), unless its stencil
    reaches a held node (`reach` = sum phi_I over held nodes > 0), where it takes the grid's
    sum phi_I T~_I. A held node's T_I^t is T* itself, not the particles' (C T)_I / C_I, so its
    FLIP increment T*(t + dt) - T*(t) never passes on the difference between the two: the
    particle next to it kept the start temperature's share of that node (half the jump of E12's
    last cell, docs/benchmarks.md "Heat"). The held node is a heat reservoir, so the heat this
    changes is what the condition supplies; the particles whose stencil reaches no held node
    keep FLIP's exact balance."""
    return grid if reach > 0.0 else T_p + change


@njit(cache=True)
def _g2p_remap_block(nodes, start, stop, idx, w, T_old, T_new, held, mass, capacity, T, remapped):
    nk = len(nodes)
    for p in range(start, stop):
        mc = mass[p] * capacity[p]
        if mc == 0.0:
            continue
        dT = 0.0
        grid = 0.0
        reach = 0.0
        for k in range(nk):
            node = idx[p, k]
            dT += w[p, k] * (T_new[node] - T_old[node])
            grid += w[p, k] * T_new[node]
            reach += w[p, k] * held[node]
        T[p] = takes_grid_temperature(reach, T[p], dT, grid)
        mct = mc * T[p]
        for k in range(nk):
            remapped[idx[p, k]] += w[p, k] * mct


@njit(parallel=True, cache=True)
def remapped_temperature(heat, remapped, cutoff, T_grid, blocks):
    """`remapped_temperature_block` over all nodes, one block a thread."""
    bounds = block_bounds(heat.shape[0], blocks)
    for t in prange(blocks):
        remapped_temperature_block(bounds[t], bounds[t + 1], heat, remapped, cutoff, T_grid)


@njit(cache=True)
def remapped_temperature_block(start, stop, heat, remapped, cutoff, T_grid):
    """T_I^{t+dt} = remapped_I / C_I^t (line 13)."""
    for i in range(start, stop):
        T_grid[i] = remapped[i] / heat[i, 0] if heat[i, 0] > cutoff else 0.0


@njit(parallel=True, cache=True)
def particle_flux(spec, idx, dw, T_grid, conductivity, flux, blocks):
    """q_p = -k_p sum_I grad phi_I(x_p^t) T_I^{t+dt} (line 15), from the remapped grid temperature."""
    dims, nodes = spec
    bounds = block_bounds(dw.shape[0], blocks)
    for t in prange(blocks):
        _flux_block(dims, nodes, bounds[t], bounds[t + 1], idx, dw, T_grid, conductivity, flux)


@njit(cache=True)
def _flux_block(dims, nodes, start, stop, idx, dw, T_grid, conductivity, flux):
    dim, nk = len(dims), len(nodes)
    for p in range(start, stop):
        k = conductivity[p]
        for a in range(dim):
            g = 0.0
            if k != 0.0:
                for n in range(nk):
                    g += dw[p, n, a] * T_grid[idx[p, n]]
            flux[p, a] = -k * g


@njit(parallel=True, cache=True)
def reference_flux(spec, idx, dw, T_grid, conductivity, F, flux, nominal, blocks):
    """TLMPM (Algorithm 8 in the reference configuration): with grad0 T = sum_I grad0 phi_I(X_p)
    T_I^{t+dt}, the spatial gradient is F^-T grad0 T; q_p = -k F^-T grad0 T (the output
    heat_flux) and the nominal flux Q_p = J F^-1 q_p, whose sum V0_p Q_p . grad0 phi_I is the
    same heat rate as sum V_p q_p . grad phi_I."""
    dims, nodes = spec
    bounds = block_bounds(dw.shape[0], blocks)
    for t in prange(blocks):
        _reference_flux_block(dims, nodes, bounds[t], bounds[t + 1], idx, dw, T_grid, conductivity, F, flux,
                              nominal)


@njit(cache=True)
def _reference_flux_block(dims, nodes, start, stop, idx, dw, T_grid, conductivity, F, flux, nominal):
    dim = len(dims)
    _flux_block(dims, nodes, start, stop, idx, dw, T_grid, conductivity, flux)   # -k grad0 T
    Finv = np.empty((dim, dim))
    q = np.empty(dim)
    for p in range(start, stop):
        J = kernels.invert(F[p], Finv)
        for a in range(dim):   # q = F^-T (-k grad0 T)
            g = 0.0
            for b in range(dim):
                g += Finv[b, a] * flux[p, b]
            q[a] = g
        for a in range(dim):
            Q = 0.0
            for b in range(dim):
                Q += Finv[a, b] * q[b]
            flux[p, a] = q[a]
            nominal[p, a] = J * Q


@njit(parallel=True, cache=True)
def thermal_energy(mass, capacity, T):
    """sum_p m_p c_p T_p: the heat the particles hold above 0 K (with constant c)."""
    total = 0.0
    for p in prange(mass.shape[0]):
        if capacity[p] != 0.0:
            total += mass[p] * capacity[p] * T[p]
    return total


@njit(cache=True)
def expand(stress, T, T_ref, alpha, bulk, total):
    """sigma_p -= 3 K alpha (T_p - T_ref,p) I: the stress of the isotropic thermal strain
    alpha dT I under isotropic elasticity ([R] 5.26: C : (alpha dT I) = 3 K alpha dT I).
    A rate model (`total` 1-D flag) takes the increment since its last stress update and
    moves T_ref on; a total one the whole change since the start."""
    rate = total.ndim == 1
    for p in range(stress.shape[0]):   # serial: cheaper than waking the threads
        if T[p] == T_ref[p]:   # no thermal strain (a body the heat has not reached): stress untouched
            continue
        s = 3.0 * bulk * alpha * (T[p] - T_ref[p])
        for a in range(3):
            stress[p, a, a] -= s
        if rate:
            T_ref[p] = T[p]
