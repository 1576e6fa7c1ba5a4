"""Numba kernels of the pore pressure (solver/pore_fluid.py) on the step's stored stencil
(idx, w, dw at x_p^t). Serial: two scatters a step over the saturated particles, cheap
beside the mechanics' passes, and free of races without per-thread copies.

The nodal array `storage` is (n_nodes, 2): the storage S_I = sum_p phi_I V_p n_p / K_w and
the storage-weighted pressure sum_p phi_I V_p (n_p / K_w) p_p; `inflow` is the flux rate
Q_I = sum_p V_p q_p . grad phi_I (the weak form of -div q; impervious faces are natural). Each
is summed over the slabs' ghost nodes after its scatter (solver/pore_fluid.py).
"""
from __future__ import annotations

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
def darcy_to_grid(idx, dw, grid_pressure, mobility, fluid_density, acc, volume, flux, inflow):
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
def squeeze_to_grid(idx, w, volume, L, compliance, pressure, squeeze):
    """squeeze_I = sum_p phi_I V_p tr(L_p) over the saturated particles: the weak form of the
    skeleton's volume change, which the nodal pressure takes as -dt squeeze_I / S_I. Returns
    sum_p V_p p_p tr(L_p), the power of the pore pressure on the mixture."""
    dim = L.shape[1]
    power = 0.0
    for p in range(idx.shape[0]):
        if compliance[p] == 0.0:
            continue
        rate = 0.0
        for a in range(dim):
            rate += L[p, a, a]
        vr = volume[p] * rate
        power += pressure[p] * vr
        for k in range(idx.shape[1]):
            squeeze[idx[p, k]] += w[p, k] * vr
    return power


@njit(cache=True)
def take_change(idx, w, change, compliance, pressure):
    """p_p += sum_I phi_I dp_I for the saturated particles (a dry one keeps its 0)."""
    for p in range(idx.shape[0]):
        if compliance[p] == 0.0:
            continue
        total = 0.0
        for k in range(idx.shape[1]):
            total += w[p, k] * change[idx[p, k]]
        pressure[p] += total
