"""Perfectly plastic Mohr-Coulomb with non-associated flow, returned in principal
stresses (de Souza Neto, Peric & Owen 2008, sec. 8.2.2, Boxes 8.4 and 8.5; the same
plane / edge / apex regions as Clausen, Damkilde & Andersen 2006). Tension positive,
principal stresses sorted s1 >= s2 >= s3.

    Phi_ij = (s_i - s_j) + (s_i + s_j) sin(phi) - 2 c cos(phi)     (plane (i, j))
    Psi_ij = (s_i - s_j) + (s_i + s_j) sin(psi)                    (its potential)

With f, n the gradients of Phi and Psi in principal space and D the elastic matrix
there (lambda + 2G on the diagonal, lambda off it), a return to the active planes A
solves   sum_b (f_a . D n_b) dg_b = Phi_a(trial)   and sets  s = s_trial - sum_b dg_b D n_b:
  1. the main plane (1, 3); kept if s1 >= s2 >= s3 after it;
  2. else the edge it crossed: s1 = s2 (planes (1, 3), (2, 3)) or s2 = s3 (planes
     (1, 3), (1, 2)); kept if both multipliers are >= 0 and s1 >= s3;
  3. else the apex s1 = s2 = s3 = c cot(phi) (none for phi = 0: Tresca).
The principal directions are those of the trial stress (isotropy), found by cyclic
Jacobi rotations. A trial stress that cannot reach the surface (a bound on Phi from
sqrt(J2) and the mean stress) skips the eigen problem. Tension cut-off m <= T as in
drucker_prager: where the return ends above T, m = T with the trial deviator, scaled
radially back to the surface at m = T where it lies outside (for Mohr-Coulomb a
simplification of the corner return: the Lode angle is kept).
"""
from __future__ import annotations

import math

import numba
import numpy as np
from solver.jit import njit, prange

from solver.materials.drucker_prager import APEX, EDGE, ELASTIC, SURFACE, TENSION
from solver.materials.kernels import objective
from solver.materials.kernels.frictional import Frictional
from solver.threads import block_bounds


@njit(cache=True)
def eigen_symmetric(A, values, V):
    """A = V diag(values) V^T by cyclic Jacobi rotations (A, 3x3 symmetric, is overwritten)."""
    for a in range(3):
        for b in range(3):
            V[a, b] = 1.0 if a == b else 0.0
    for _ in range(30):
        off = A[0, 1] * A[0, 1] + A[0, 2] * A[0, 2] + A[1, 2] * A[1, 2]
        diagonal = A[0, 0] * A[0, 0] + A[1, 1] * A[1, 1] + A[2, 2] * A[2, 2]
        if off <= 1e-36 * diagonal or off == 0.0:
            break
        for p, q in ((0, 1), (0, 2), (1, 2)):
            _rotate(A, V, p, q)
    for a in range(3):
        values[a] = A[a, a]


@njit(cache=True)
def _rotate(A, V, p, q):
    """One Jacobi rotation zeroing A[p, q] (Numerical Recipes 11.1)."""
    apq = A[p, q]
    if apq == 0.0:
        return
    theta = (A[q, q] - A[p, p]) / (2.0 * apq)
    if abs(theta) > 1e150:
        t = 0.5 / theta
    else:
        t = (1.0 if theta >= 0.0 else -1.0) / (abs(theta) + math.sqrt(theta * theta + 1.0))
    c = 1.0 / math.sqrt(t * t + 1.0)
    s = t * c
    A[p, p] -= t * apq
    A[q, q] += t * apq
    A[p, q] = 0.0
    A[q, p] = 0.0
    r = 3 - p - q
    arp, arq = A[r, p], A[r, q]
    A[r, p] = A[p, r] = c * arp - s * arq
    A[r, q] = A[q, r] = s * arp + c * arq
    for k in range(3):
        vkp, vkq = V[k, p], V[k, q]
        V[k, p] = c * vkp - s * vkq
        V[k, q] = s * vkp + c * vkq


@njit(cache=True)
def sort_descending(values, order):
    """order = the indices of `values` from the largest down (three values, no allocation)."""
    order[0], order[1], order[2] = 0, 1, 2
    for i, j in ((0, 1), (1, 2), (0, 1)):
        if values[order[j]] > values[order[i]]:
            order[i], order[j] = order[j], order[i]


@njit(cache=True)
def plane_value(sig, i, j, sin_phi, two_c_cos):
    return (sig[i] - sig[j]) + (sig[i] + sig[j]) * sin_phi - two_c_cos


@njit(cache=True)
def _gradient(i, j, sin_x, out):
    """d/dsigma of (s_i - s_j) + (s_i + s_j) sin_x."""
    out[0] = out[1] = out[2] = 0.0
    out[i] = 1.0 + sin_x
    out[j] = -(1.0 - sin_x)


@njit(cache=True)
def _elastic_times(n, lam, G, out):
    """D n in principal space."""
    tr = lam * (n[0] + n[1] + n[2])
    for k in range(3):
        out[k] = tr + 2.0 * G * n[k]


@njit(cache=True)
def _return_to_planes(trial, planes, count, lam, G, sin_phi, sin_psi, two_c_cos, sig, scratch):
    """sig = trial - sum_b dg_b D n_b with every plane of `planes[:count]` satisfied;
    returns the smallest multiplier (negative: the return left this region)."""
    f, n, Dn = scratch[0], scratch[1], scratch[2:4]
    M, rhs = scratch[4:6, :2], scratch[6, :2]
    for b in range(count):
        _gradient(planes[b, 0], planes[b, 1], sin_psi, n)
        _elastic_times(n, lam, G, Dn[b])
    for a in range(count):
        _gradient(planes[a, 0], planes[a, 1], sin_phi, f)
        rhs[a] = plane_value(trial, planes[a, 0], planes[a, 1], sin_phi, two_c_cos)
        for b in range(count):
            M[a, b] = f[0] * Dn[b, 0] + f[1] * Dn[b, 1] + f[2] * Dn[b, 2]
    if count == 1:
        dg0, dg1 = rhs[0] / M[0, 0], 0.0
    else:
        det = M[0, 0] * M[1, 1] - M[0, 1] * M[1, 0]
        dg0 = (M[1, 1] * rhs[0] - M[0, 1] * rhs[1]) / det
        dg1 = (M[0, 0] * rhs[1] - M[1, 0] * rhs[0]) / det
    for k in range(3):
        sig[k] = trial[k] - dg0 * Dn[0, k] - (dg1 * Dn[1, k] if count == 2 else 0.0)
    return min(dg0, dg1)


@njit(cache=True)
def return_map(trial, lam, G, sin_phi, sin_psi, cohesion, cutoff, sig, planes, scratch):
    """Principal stresses `sig` after the return from `trial` (both sorted descending);
    returns the yield state."""
    two_c_cos = 2.0 * cohesion * math.sqrt(1.0 - sin_phi * sin_phi)
    for k in range(3):
        sig[k] = trial[k]
    where = ELASTIC
    if plane_value(trial, 0, 2, sin_phi, two_c_cos) > 0.0:
        planes[0, 0], planes[0, 1] = 0, 2
        _return_to_planes(trial, planes, 1, lam, G, sin_phi, sin_psi, two_c_cos, sig, scratch)
        where = SURFACE
        if sig[1] > sig[0] or sig[2] > sig[1]:
            if sig[1] - sig[0] > sig[2] - sig[1]:     # crossed s1 = s2
                planes[1, 0], planes[1, 1] = 1, 2
            else:                                   # crossed s2 = s3
                planes[1, 0], planes[1, 1] = 0, 1
            least = _return_to_planes(trial, planes, 2, lam, G, sin_phi, sin_psi, two_c_cos, sig, scratch)
            where = EDGE
            if sin_phi > 0.0 and (least < 0.0 or sig[0] < sig[2]):
                apex = 0.5 * two_c_cos / sin_phi
                sig[0] = sig[1] = sig[2] = apex
                where = APEX
    if (sig[0] + sig[1] + sig[2]) / 3.0 > cutoff:
        where = _cut_off(trial, sin_phi, two_c_cos, cutoff, sig)
    return where


@njit(cache=True)
def _cut_off(trial, sin_phi, two_c_cos, cutoff, sig):
    """The mean stress at the cut-off T with the trial deviator, scaled radially back to
    the surface at mean stress T where it lies outside."""
    m = (trial[0] + trial[1] + trial[2]) / 3.0
    d0, d2 = trial[0] - m, trial[2] - m
    radius = (d0 - d2) + (d0 + d2) * sin_phi      # Phi(T + d) - Phi(T) per unit of the deviator d
    alpha = 1.0
    if radius > 0.0:
        alpha = min(1.0, (two_c_cos - 2.0 * cutoff * sin_phi) / radius)
    for k in range(3):
        sig[k] = cutoff + alpha * (trial[k] - m)
    return TENSION


@njit(cache=True)
def may_yield(q, m, sin_phi, two_c_cos):
    """False when no Lode angle puts the stress (von Mises q, mean m) outside the surface:
    s1 - s3 <= 2 sqrt(J2) and s1 + s3 <= 2 m + sqrt(J2 / 3)."""
    j = q / math.sqrt(3.0)
    return 2.0 * j + (2.0 * m + j / math.sqrt(3.0)) * sin_phi - two_c_cos > 0.0


@njit(parallel=True, cache=True)
def _update(L, stress, eps_p, state, volume, work, dt, K, G, sin_phi, sin_psi, cohesion, cutoff, threads):
    bounds = block_bounds(L.shape[0], threads)
    for t in prange(threads):
        _update_block(bounds[t], bounds[t + 1], L, stress, eps_p, state, volume, work, dt, K, G, sin_phi, sin_psi,
                      cohesion, cutoff)


@njit(cache=True)
def _update_block(lo, hi, L, stress, eps_p, state, volume, work, dt, K, G, sin_phi, sin_psi, cohesion, cutoff):
    # scratch per block, in this serial function: never shared between threads
    A, V = np.empty((3, 3)), np.empty((3, 3))
    values, trial, sig = np.empty(3), np.empty(3), np.empty(3)
    planes, scratch, order = np.empty((2, 2), np.int64), np.empty((7, 3)), np.empty(3, np.int64)
    lam = K - 2.0 * G / 3.0
    two_c_cos = 2.0 * cohesion * math.sqrt(1.0 - sin_phi * sin_phi)
    for p in range(lo, hi):
        # the Jaumann trial stress in nine scalars (kernels/objective.py says why)
        D, w21, w02, w10 = objective.rate_parts(L[p])
        sigma = objective.rotated(stress[p], w21, w02, w10, dt)
        m = -(objective.mean_pressure(sigma) - K * objective.trace(D) * dt)
        s = objective.trial_deviator(sigma, D, 2.0 * G * dt)
        objective.assemble_from(s, -m, stress[p])
        state[p] = ELASTIC
        if not (may_yield(objective.von_mises_of(s), m, sin_phi, two_c_cos) or m > cutoff):
            continue
        for a in range(3):
            for b in range(3):
                A[a, b] = stress[p, a, b]
        eigen_symmetric(A, values, V)
        sort_descending(values, order)
        for k in range(3):
            trial[k] = values[order[k]]
        state[p] = return_map(trial, lam, G, sin_phi, sin_psi, cohesion, cutoff, sig, planes, scratch)
        if state[p] != ELASTIC:
            d_eps, d_work = _plastic_increments(trial, sig, K, G)
            eps_p[p] += d_eps
            work[p] += volume[p] * d_work
            for k in range(3):        # sigma += sum_k (s_k - trial_k) v_k v_k^T: exact off the changed part
                dk, i = sig[k] - trial[k], order[k]
                for a in range(3):
                    for b in range(3):
                        stress[p, a, b] += dk * V[a, i] * V[b, i]


@njit(cache=True)
def _plastic_increments(trial, sig, K, G):
    """The return's plastic strain increment de_p = C^-1 : (trial - sig) in principal space:
    its equivalent sqrt(2/3 dev(de_p) : dev(de_p)) and its work at the returned stress,
    sig : de_p = s : dev(de_p) + m tr(de_p) = s : dev(de_p) + m dm / K."""
    mean = (trial[0] - sig[0] + trial[1] - sig[1] + trial[2] - sig[2]) / 3.0
    stress_mean = (sig[0] + sig[1] + sig[2]) / 3.0
    total = 0.0
    work = 0.0
    for k in range(3):
        e = (trial[k] - sig[k] - mean) / (2.0 * G)
        total += e * e
        work += (sig[k] - stress_mean) * e
    return math.sqrt(2.0 / 3.0 * total), work + stress_mean * mean / K


class MohrCoulomb(Frictional):
    def update_stress(self, particles, sl: slice, dt: float) -> None:
        _update(particles.L[sl], particles.stress[sl], particles.extra["plastic_strain"][sl],
                particles.extra["yield_state"][sl], particles.volume[sl], particles.extra["plastic_work"][sl],
                dt, self.bulk, self.mu, self.sin_phi, self.sin_psi,
                self.cohesion, self.tension_cutoff, numba.get_num_threads())
