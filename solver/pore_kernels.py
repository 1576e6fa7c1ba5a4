"""Numba kernels of the pore pressure (solver/pore_fluid.py): four passes a step over the
saturated particles, serial (free of races without per-thread copies). Each comes twice:
on the general backend's stored stencil (idx, w, dw at x_p^t: each takes all three and reads
what it needs: `pressure_to_grid` ...), and,
for the fused backend, which stores none, with each particle's weights formed in the pass
from x_p^t (`pressure_to_grid_at` ...: `_stencil_at`), the same bits as the stored ones for
linear hats and quadratic B-splines. The four cost what the stored-stencil passes do (0.97x
in 2D, 0.87x in 3D on benchmarks/two_phase.py's layers); what they save is the stencil the
fused mechanics would otherwise store and read. The weights are tuples, which stay in
registers: formed into per-particle scratch rows instead, the passes were 5-8x slower.

The nodal array `storage` is (n_nodes, 2): the storage S_I = sum_p phi_I V_p n_p / K_w and
the storage-weighted pressure sum_p phi_I V_p (n_p / K_w) p_p; `inflow` is the flux rate
Q_I = sum_p V_p q_p . grad phi_I (the weak form of -div q; impervious faces are natural). Each
is summed over the slabs' ghost nodes after its scatter (solver/pore_fluid.py).
"""
from __future__ import annotations

from solver.fused import _axis
from solver.jit import njit


@njit(cache=True)
def pressure_to_grid(idx, w, dw, volume, compliance, pressure, storage, force):
    """S_I and (S p)_I, and the pore pressure's share of the internal force: the total stress
    is sigma' - p I, so f_I += sum_p V_p p_p grad phi_I (the material's P2G took sigma')."""
    dim = dw.shape[2]
    for p in range(idx.shape[0]):
        s = volume[p] * compliance[p]
        if s == 0.0:   # a dry material
            continue
        vp = volume[p] * pressure[p]
        for k in range(idx.shape[1]):
            node = idx[p, k]
            storage[node, 0] += w[p, k] * s
            storage[node, 1] += w[p, k] * s * pressure[p]
            for a in range(dim):
                force[node, a] += vp * dw[p, k, a]


@njit(cache=True)
def darcy_to_grid(idx, w, dw, grid_pressure, mobility, fluid_density, acc, volume, flux, inflow):
    """q_p = -(k / (rho_w g_n)) (grad p - rho_w b_p) with grad p = sum_I p_I grad phi_I(x_p)
    (Darcy), and Q_I += V_p q_p . grad phi_I. acc: the step's body acceleration b, a row a
    particle or one row for all."""
    dim = dw.shape[2]
    shared = acc.shape[0] == 1
    for p in range(idx.shape[0]):
        if mobility[p] == 0.0:
            continue
        row = 0 if shared else p
        for a in range(dim):
            gradient = 0.0
            for k in range(idx.shape[1]):
                gradient += grid_pressure[idx[p, k]] * dw[p, k, a]
            flux[p, a] = -mobility[p] * (gradient - fluid_density[p] * acc[row, a])
        for k in range(idx.shape[1]):
            q = 0.0
            for a in range(dim):
                q += flux[p, a] * dw[p, k, a]
            inflow[idx[p, k]] += volume[p] * q


@njit(cache=True)
def squeeze_to_grid(idx, w, dw, volume, L, compliance, pressure, squeeze):
    """squeeze_I = sum_p phi_I V_p tr(L_p) over the saturated particles: the weak form of the
    skeleton's volume change, which the nodal pressure takes as -dt squeeze_I / S_I. Returns
    sum_p V_p p_p tr(L_p), the power of the pore pressure on the mixture."""
    power = 0.0
    for p in range(idx.shape[0]):
        if compliance[p] == 0.0:
            continue
        vr = volume[p] * _trace(L, p)
        power += pressure[p] * vr
        for k in range(idx.shape[1]):
            squeeze[idx[p, k]] += w[p, k] * vr
    return power


@njit(cache=True)
def _trace(L, p):
    """tr(L_p): the rate of the skeleton's volume change per unit volume."""
    rate = 0.0
    for a in range(L.shape[1]):
        rate += L[p, a, a]
    return rate


@njit(cache=True)
def take_change(idx, w, dw, change, compliance, pressure):
    """p_p += sum_I phi_I dp_I for the saturated particles (a dry one keeps its 0)."""
    for p in range(idx.shape[0]):
        if compliance[p] == 0.0:
            continue
        total = 0.0
        for k in range(idx.shape[1]):
            total += w[p, k] * change[idx[p, k]]
        pressure[p] += total


# -- with the weights formed in the pass (the fused backend) ---------------------------------


@njit(cache=True, inline="always")
def _stencil_at(x, p, dims, support, frame, wanted):
    """The stencil of particle p at x[p] as (taken, first node, nodes per axis, node strides,
    1D weights, 1D derivatives), three axes each (a 2D one's third: one node, weight 1, so that
    the products are tensor.scatter's to the bit, in its order); fused._axis's 1D weights are
    the shape modules'. Not taken where not `wanted` (a dry particle) or outside the grid."""
    lower, inv_h, cells, strides, offset = frame
    if not wanted:
        unit = (0.0, 0.0, 0.0)
        return False, 0, (0, 0, 0), (0, 0, 0), (unit, unit, unit), (unit, unit, unit)
    ok0, i0, _, w0, g0 = _axis(support, x[p, 0], lower[0], inv_h[0], cells[0])
    ok1, i1, _, w1, g1 = _axis(support, x[p, 1], lower[1], inv_h[1], cells[1])
    first = i0 * strides[0] + i1 * strides[1] - offset
    if len(dims) == 2:
        unit, flat = (1.0, 0.0, 0.0), (0.0, 0.0, 0.0)
        return (ok0 and ok1, first, (support, support, 1), (strides[0], strides[1], 0), (w0, w1, unit),
                (g0, g1, flat))
    ok2, i2, _, w2, g2 = _axis(support, x[p, 2], lower[2], inv_h[2], cells[2])
    return (ok0 and ok1 and ok2, first + i2 * strides[2], (support, support, support),
            (strides[0], strides[1], strides[2]), (w0, w1, w2), (g0, g1, g2))


@njit(cache=True)
def pressure_to_grid_at(nodes, dims, frame, x, volume, compliance, pressure, storage, force):
    """`pressure_to_grid`, each particle's weights formed at x (x_p^t); `nodes`: an empty
    array of the support's rank (tensor.nodes_of), `dims` the stencil spec's axes."""
    dim = len(dims)
    for p in range(x.shape[0]):
        s = volume[p] * compliance[p]
        taken, first, span, stride, w, g = _stencil_at(x, p, dims, nodes.ndim, frame, s != 0.0)
        if not taken:
            continue
        vp = volume[p] * pressure[p]
        for k in range(span[2]):
            for j in range(span[1]):
                for i in range(span[0]):
                    node = first + i * stride[0] + j * stride[1] + k * stride[2]
                    wk = w[0][i] * w[1][j] * w[2][k]
                    storage[node, 0] += wk * s
                    storage[node, 1] += wk * s * pressure[p]
                    gradient = (g[0][i] * w[1][j] * w[2][k], w[0][i] * g[1][j] * w[2][k], w[0][i] * w[1][j] * g[2][k])
                    for a in range(dim):
                        force[node, a] += vp * gradient[a]


@njit(cache=True)
def darcy_to_grid_at(nodes, dims, frame, x, grid_pressure, mobility, fluid_density, acc, volume, flux, inflow):
    """`darcy_to_grid`, each particle's weights formed at x (x_p^t)."""
    dim = len(dims)
    shared = acc.shape[0] == 1
    for p in range(x.shape[0]):
        taken, first, span, stride, w, g = _stencil_at(x, p, dims, nodes.ndim, frame, mobility[p] != 0.0)
        if not taken:
            continue
        row = 0 if shared else p
        along_x = along_y = along_z = 0.0   # grad p, each axis summed in the stored kernel's node order
        for k in range(span[2]):
            for j in range(span[1]):
                for i in range(span[0]):
                    value = grid_pressure[first + i * stride[0] + j * stride[1] + k * stride[2]]
                    along_x += value * (g[0][i] * w[1][j] * w[2][k])
                    along_y += value * (w[0][i] * g[1][j] * w[2][k])
                    along_z += value * (w[0][i] * w[1][j] * g[2][k])
        gradient = (along_x, along_y, along_z)
        for a in range(dim):
            flux[p, a] = -mobility[p] * (gradient[a] - fluid_density[p] * acc[row, a])
        q_z = flux[p, 2] if dim == 3 else 0.0
        for k in range(span[2]):
            for j in range(span[1]):
                for i in range(span[0]):
                    q = flux[p, 0] * (g[0][i] * w[1][j] * w[2][k]) + flux[p, 1] * (w[0][i] * g[1][j] * w[2][k])
                    if dim == 3:
                        q += q_z * (w[0][i] * w[1][j] * g[2][k])
                    inflow[first + i * stride[0] + j * stride[1] + k * stride[2]] += volume[p] * q


@njit(cache=True)
def squeeze_to_grid_at(nodes, dims, frame, x, volume, L, compliance, pressure, squeeze):
    """`squeeze_to_grid`, each particle's weights formed at x (x_p^t)."""
    power = 0.0
    for p in range(x.shape[0]):
        taken, first, span, stride, w, _ = _stencil_at(x, p, dims, nodes.ndim, frame, compliance[p] != 0.0)
        if not taken:
            continue
        vr = volume[p] * _trace(L, p)
        power += pressure[p] * vr
        for k in range(span[2]):
            for j in range(span[1]):
                for i in range(span[0]):
                    squeeze[first + i * stride[0] + j * stride[1] + k * stride[2]] += w[0][i] * w[1][j] * w[2][k] * vr
    return power


@njit(cache=True)
def take_change_at(nodes, dims, frame, x, change, compliance, pressure):
    """`take_change`, each particle's weights formed at x (x_p^t)."""
    for p in range(x.shape[0]):
        taken, first, span, stride, w, _ = _stencil_at(x, p, dims, nodes.ndim, frame, compliance[p] != 0.0)
        if not taken:
            continue
        total = 0.0
        for k in range(span[2]):
            for j in range(span[1]):
                for i in range(span[0]):
                    total += w[0][i] * w[1][j] * w[2][k] * change[first + i * stride[0] + j * stride[1] + k * stride[2]]
        pressure[p] += total
