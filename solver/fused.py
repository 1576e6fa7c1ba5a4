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

Each kernel runs one contiguous block of particles per thread; P2G scatters
into per-thread copies of the nodal arrays, summed afterwards (solver/threads.py).

What a kernel does (the support S = 2 for linear, 3 for quadratic B-splines; the
G2P mode; APIC or not; a FLIP blend or not; a body force or not) reaches it as
the number of dimensions of small empty arrays (`constant`): numba compiles one
specialisation per array type, so inside the threads' loops these are
compile-time constants and the branches of the other variants fold away. Plain
arguments would be runtime values there (numba passes what a prange loop uses to
the threads' function as arguments; measured, runtime flags made P2G 20 %
slower), and an empty tuple, whose length would say the same, cannot be passed in.
"""
from __future__ import annotations

import numpy as np
from numba import njit, prange

from solver.kernels import determinant
from solver.threads import add_copies, add_node_copies, block_bounds, own

FUSED_SHAPES = {"linear": 2, "quadratic_bspline": 3}
_TOUCH = 1e-9   # as solver/shape/quadratic_bspline.py: round-off allowance at h/2 from a grid end


def applies(scene) -> bool:
    """Whether the scene's step is one the fused kernels implement."""
    method = scene.method
    return (method.formulation == "ulmpm" and method.scheme in ("usl", "musl")
            and method.shape_function in FUSED_SHAPES and not scene.axisymmetric
            and scene.dimension in (2, 3)
            and not any(m.model == "rigid" for m in scene.materials.values()))


_CONSTANTS = [np.empty((0,) * n) for n in range(1, 5)]


def constant(value: int) -> np.ndarray:
    """An empty array of value + 1 dimensions: `value` as a compile-time constant
    (read back as `array.ndim - 1`, see the module docstring)."""
    return _CONSTANTS[int(value)]


def support_of(shape_function: str) -> np.ndarray:
    return constant(FUSED_SHAPES[shape_function])


# -- weights along one axis ------------------------------------------------------

@njit(cache=True)
def _axis(S, x, lower, inv_h, cells):
    """First node i, position in cells from it f, 1D weights and derivatives (times
    inv_h) of a position along one axis, exactly as solver/shape/linear.py and
    quadratic_bspline.py compute them; `ok` is False outside the grid (or NaN).
    Node i + j lies at (j - f) h from the particle."""
    s = (x - lower) * inv_h
    if S == 2:
        ok = s >= 0.0 and s <= cells
        i = min(int(s), cells - 1) if ok else 0
        f = s - i
        return ok, i, f, (1.0 - f, f, 0.0), (-inv_h, inv_h, 0.0)
    ok = s >= 0.5 - _TOUCH and s <= cells - 0.5 + _TOUCH
    i = min(max(int(s - 0.5), 0), cells - 2) if ok else 0
    f = s - i
    return (ok, i, f, (0.5 * (1.5 - f) ** 2, 0.75 - (f - 1.0) ** 2, 0.5 * (f - 0.5) ** 2),
            (-(1.5 - f) * inv_h, -2.0 * (f - 1.0) * inv_h, (f - 0.5) * inv_h))


@njit(cache=True)
def _reduce(grid_mass, grid_mom, grid_force, copies_mass, copies_mom, copies_force):
    if copies_mass.shape[0] > 0:
        add_copies(grid_mass, grid_mom, grid_force, copies_mass, copies_mom, copies_force)


# -- P2G ---------------------------------------------------------------------------

@njit(parallel=True, cache=True)
def p2g_2d(support, affine_, loaded_, x, v, C, mass, volume, stress, acc, lower, h, inv_h, cells, strides, offset,
           grid_mass, grid_mom, grid_force, copies_mass, copies_mom, copies_force, bad):
    """m_I, (mv)_I (with the APIC term m w C (x_I - x_p) when `affine`) and f_I =
    sum_p m_p w b_p - V_p sigma_p grad w. bad[t]: first particle of block t outside the grid."""
    threads = copies_mass.shape[0] + 1
    bounds = block_bounds(x.shape[0], threads)
    shared_acc = acc.shape[0] == 1
    for t in prange(threads):
        S, affine, loaded = support.ndim - 1, affine_.ndim == 2, loaded_.ndim == 2   # compile-time constants
        gm, gp, gf = own(t, grid_mass, copies_mass), own(t, grid_mom, copies_mom), own(t, grid_force, copies_force)
        bad[t] = -1
        for p in range(bounds[t], bounds[t + 1]):
            okx, ix, fx, wx, gx = _axis(S, x[p, 0], lower[0], inv_h[0], cells[0])
            oky, iy, fy, wy, gy = _axis(S, x[p, 1], lower[1], inv_h[1], cells[1])
            if not (okx and oky):      # (no break: an early exit slows the whole loop)
                if bad[t] < 0:
                    bad[t] = p
                continue
            m = mass[p]
            ap = 0 if shared_acc else p
            max_, may = m * acc[ap, 0], m * acc[ap, 1]
            vol = volume[p]
            sxx, sxy, syx, syy = vol * stress[p, 0, 0], vol * stress[p, 0, 1], vol * stress[p, 1, 0], vol * stress[p, 1, 1]
            mvx, mvy = m * v[p, 0], m * v[p, 1]
            mc00 = mc01 = mc10 = mc11 = 0.0   # m_p C_p (C holds one placeholder row without APIC)
            if affine:
                mc00, mc01, mc10, mc11 = m * C[p, 0, 0], m * C[p, 0, 1], m * C[p, 1, 0], m * C[p, 1, 1]
            for j in range(S):
                dy = (j - fy) * h[1]
                row = (iy + j) * strides[1] - offset
                for i in range(S):
                    node = row + ix + i   # (strides[0] is 1: x fastest)
                    w = wx[i] * wy[j]
                    dwx = gx[i] * wy[j]
                    dwy = wx[i] * gy[j]
                    px, py = mvx, mvy
                    if affine:
                        dx = (i - fx) * h[0]
                        px += mc00 * dx + mc01 * dy
                        py += mc10 * dx + mc11 * dy
                    gm[node] += w * m
                    gp[node, 0] += w * px
                    gp[node, 1] += w * py
                    if loaded:
                        gf[node, 0] += w * max_ - sxx * dwx - sxy * dwy
                        gf[node, 1] += w * may - syx * dwx - syy * dwy
                    else:
                        gf[node, 0] -= sxx * dwx + sxy * dwy
                        gf[node, 1] -= syx * dwx + syy * dwy
    _reduce(grid_mass, grid_mom, grid_force, copies_mass, copies_mom, copies_force)


@njit(parallel=True, cache=True)
def p2g_3d(support, affine_, loaded_, x, v, C, mass, volume, stress, acc, lower, h, inv_h, cells, strides, offset,
           grid_mass, grid_mom, grid_force, copies_mass, copies_mom, copies_force, bad):
    """p2g_2d in 3D."""
    threads = copies_mass.shape[0] + 1
    bounds = block_bounds(x.shape[0], threads)
    shared_acc = acc.shape[0] == 1
    for t in prange(threads):
        S, affine, loaded = support.ndim - 1, affine_.ndim == 2, loaded_.ndim == 2   # compile-time constants
        gm, gp, gf = own(t, grid_mass, copies_mass), own(t, grid_mom, copies_mom), own(t, grid_force, copies_force)
        bad[t] = -1
        for p in range(bounds[t], bounds[t + 1]):
            okx, ix, fx, wx, gx = _axis(S, x[p, 0], lower[0], inv_h[0], cells[0])
            oky, iy, fy, wy, gy = _axis(S, x[p, 1], lower[1], inv_h[1], cells[1])
            okz, iz, fz, wz, gz = _axis(S, x[p, 2], lower[2], inv_h[2], cells[2])
            if not (okx and oky and okz):
                if bad[t] < 0:
                    bad[t] = p
                continue
            m = mass[p]
            ap = 0 if shared_acc else p
            max_, may, maz = m * acc[ap, 0], m * acc[ap, 1], m * acc[ap, 2]
            mvx, mvy, mvz = m * v[p, 0], m * v[p, 1], m * v[p, 2]
            vol = volume[p]
            s00, s01, s02 = vol * stress[p, 0, 0], vol * stress[p, 0, 1], vol * stress[p, 0, 2]
            s10, s11, s12 = vol * stress[p, 1, 0], vol * stress[p, 1, 1], vol * stress[p, 1, 2]
            s20, s21, s22 = vol * stress[p, 2, 0], vol * stress[p, 2, 1], vol * stress[p, 2, 2]
            mc00 = mc01 = mc02 = mc10 = mc11 = mc12 = mc20 = mc21 = mc22 = 0.0   # m_p C_p, as in 2D
            if affine:
                mc00, mc01, mc02 = m * C[p, 0, 0], m * C[p, 0, 1], m * C[p, 0, 2]
                mc10, mc11, mc12 = m * C[p, 1, 0], m * C[p, 1, 1], m * C[p, 1, 2]
                mc20, mc21, mc22 = m * C[p, 2, 0], m * C[p, 2, 1], m * C[p, 2, 2]
            for k in range(S):
                dz = (k - fz) * h[2]
                for j in range(S):
                    dy = (j - fy) * h[1]
                    row = (iy + j) * strides[1] + (iz + k) * strides[2] - offset
                    wyz, gyz, wygz = wy[j] * wz[k], gy[j] * wz[k], wy[j] * gz[k]
                    for i in range(S):
                        node = row + ix + i   # (strides[0] is 1: x fastest)
                        w = wx[i] * wyz
                        dwx = gx[i] * wyz
                        dwy = wx[i] * gyz
                        dwz = wx[i] * wygz
                        px, py, pz = mvx, mvy, mvz
                        if affine:
                            dx = (i - fx) * h[0]
                            px += mc00 * dx + mc01 * dy + mc02 * dz
                            py += mc10 * dx + mc11 * dy + mc12 * dz
                            pz += mc20 * dx + mc21 * dy + mc22 * dz
                        gm[node] += w * m
                        gp[node, 0] += w * px
                        gp[node, 1] += w * py
                        gp[node, 2] += w * pz
                        if loaded:
                            gf[node, 0] += w * max_ - s00 * dwx - s01 * dwy - s02 * dwz
                            gf[node, 1] += w * may - s10 * dwx - s11 * dwy - s12 * dwz
                            gf[node, 2] += w * maz - s20 * dwx - s21 * dwy - s22 * dwz
                        else:
                            gf[node, 0] -= s00 * dwx + s01 * dwy + s02 * dwz
                            gf[node, 1] -= s10 * dwx + s11 * dwy + s12 * dwz
                            gf[node, 2] -= s20 * dwx + s21 * dwy + s22 * dwz
    _reduce(grid_mass, grid_mom, grid_force, copies_mass, copies_mom, copies_force)


# -- G2P ---------------------------------------------------------------------------

USL, REMAP, KINEMATICS = 0, 1, 2   # what a g2p kernel does, see the module docstring


@njit(parallel=True, cache=True)
def g2p_2d(support, mode_, affine_, blend_, x, v, C, flip, dt, mass, lower, h, inv_h, cells, strides, offset,
           v_old, v_new, L, F, volume, volume0, rate, grid_mom, copies_mom, bad):
    """USL: v_p (PIC/FLIP blend), C_p = B_p D_p^-1, x_p += dt v_pic, and L_p, F_p, V_p
    from v_new. REMAP: v_p and C_p only, v_pic into `rate`, and the new momentum
    m w (v_p + C_p (x_I - x_p)) added to grid_mom (zeroed by the caller). KINEMATICS:
    L_p, F_p, V_p from v_new (the remapped velocity), then x_p += dt rate_p.
    bad[t]: first particle of block t whose J = det F is not positive."""
    threads = copies_mom.shape[0] + 1
    bounds = block_bounds(x.shape[0], threads)
    remaps = mode_.ndim - 1 == REMAP
    d_inv0, d_inv1 = 4.0 * inv_h[0] * inv_h[0], 4.0 * inv_h[1] * inv_h[1]   # quadratic B-splines: D_p = h^2/4
    for t in prange(threads):
        S, affine, blend = support.ndim - 1, affine_.ndim == 2, blend_.ndim == 2   # compile-time constants
        mode = mode_.ndim - 1
        gp = own(t, grid_mom, copies_mom) if mode == REMAP else grid_mom
        bad[t] = -1
        for p in range(bounds[t], bounds[t + 1]):
            _, ix, fx, wx, gx = _axis(S, x[p, 0], lower[0], inv_h[0], cells[0])
            _, iy, fy, wy, gy = _axis(S, x[p, 1], lower[1], inv_h[1], cells[1])
            vpx = vpy = dvx = dvy = 0.0
            b00 = b01 = b10 = b11 = 0.0
            l00 = l01 = l10 = l11 = 0.0
            for j in range(S):
                dy = (j - fy) * h[1]
                row = (iy + j) * strides[1] - offset
                for i in range(S):
                    node = row + ix + i   # (strides[0] is 1: x fastest)
                    w = wx[i] * wy[j]
                    vx, vy = v_new[node, 0], v_new[node, 1]
                    if mode == KINEMATICS:
                        dwx = gx[i] * wy[j]
                        dwy = wx[i] * gy[j]
                        l00 += vx * dwx
                        l01 += vx * dwy
                        l10 += vy * dwx
                        l11 += vy * dwy
                        continue
                    vpx += w * vx
                    vpy += w * vy
                    if blend:
                        dvx += w * (vx - v_old[node, 0])
                        dvy += w * (vy - v_old[node, 1])
                    if affine:
                        dx = (i - fx) * h[0]
                        b00 += vx * w * dx
                        b01 += vx * w * dy
                        b10 += vy * w * dx
                        b11 += vy * w * dy
                    if mode == USL:
                        dwx = gx[i] * wy[j]
                        dwy = wx[i] * gy[j]
                        l00 += vx * dwx
                        l01 += vx * dwy
                        l10 += vy * dwx
                        l11 += vy * dwy
            if mode != KINEMATICS:
                if blend:
                    v[p, 0] = flip * (v[p, 0] + dvx) + (1.0 - flip) * vpx
                    v[p, 1] = flip * (v[p, 1] + dvy) + (1.0 - flip) * vpy
                else:
                    v[p, 0], v[p, 1] = vpx, vpy
                if affine:
                    C[p, 0, 0], C[p, 0, 1] = b00 * d_inv0, b01 * d_inv1
                    C[p, 1, 0], C[p, 1, 1] = b10 * d_inv0, b11 * d_inv1
            if mode == REMAP:
                rate[p, 0], rate[p, 1] = vpx, vpy
                m = mass[p]
                for j in range(S):
                    dy = (j - fy) * h[1]
                    row = (iy + j) * strides[1] - offset
                    for i in range(S):
                        node = row + ix + i   # (strides[0] is 1: x fastest)
                        mw = m * (wx[i] * wy[j])
                        px, py = v[p, 0], v[p, 1]
                        if affine:
                            dx = (i - fx) * h[0]
                            px += C[p, 0, 0] * dx + C[p, 0, 1] * dy
                            py += C[p, 1, 0] * dx + C[p, 1, 1] * dy
                        gp[node, 0] += mw * px
                        gp[node, 1] += mw * py
                continue
            if mode == USL:
                x[p, 0] += dt * vpx
                x[p, 1] += dt * vpy
            else:
                x[p, 0] += dt * rate[p, 0]
                x[p, 1] += dt * rate[p, 1]
            L[p, 0, 0], L[p, 0, 1], L[p, 1, 0], L[p, 1, 1] = l00, l01, l10, l11
            f00, f01, f10, f11 = F[p, 0, 0], F[p, 0, 1], F[p, 1, 0], F[p, 1, 1]
            F[p, 0, 0] = f00 + dt * l00 * f00 + dt * l01 * f10
            F[p, 0, 1] = f01 + dt * l00 * f01 + dt * l01 * f11
            F[p, 1, 0] = f10 + dt * l10 * f00 + dt * l11 * f10
            F[p, 1, 1] = f11 + dt * l10 * f01 + dt * l11 * f11
            J = F[p, 0, 0] * F[p, 1, 1] - F[p, 0, 1] * F[p, 1, 0]
            volume[p] = J * volume0[p]
            if J <= 0.0 and bad[t] < 0:
                bad[t] = p
    if remaps and copies_mom.shape[0] > 0:
        add_node_copies(grid_mom, copies_mom)


@njit(parallel=True, cache=True)
def g2p_3d(support, mode_, affine_, blend_, x, v, C, flip, dt, mass, lower, h, inv_h, cells, strides, offset,
           v_old, v_new, L, F, volume, volume0, rate, grid_mom, copies_mom, bad):
    """g2p_2d in 3D."""
    threads = copies_mom.shape[0] + 1
    bounds = block_bounds(x.shape[0], threads)
    remaps = mode_.ndim - 1 == REMAP
    d_inv0, d_inv1, d_inv2 = 4.0 * inv_h[0] * inv_h[0], 4.0 * inv_h[1] * inv_h[1], 4.0 * inv_h[2] * inv_h[2]
    for t in prange(threads):
        S, affine, blend = support.ndim - 1, affine_.ndim == 2, blend_.ndim == 2   # compile-time constants
        mode = mode_.ndim - 1
        gp = own(t, grid_mom, copies_mom) if mode == REMAP else grid_mom
        bad[t] = -1
        for p in range(bounds[t], bounds[t + 1]):
            _, ix, fx, wx, gx = _axis(S, x[p, 0], lower[0], inv_h[0], cells[0])
            _, iy, fy, wy, gy = _axis(S, x[p, 1], lower[1], inv_h[1], cells[1])
            _, iz, fz, wz, gz = _axis(S, x[p, 2], lower[2], inv_h[2], cells[2])
            vpx = vpy = vpz = dvx = dvy = dvz = 0.0
            b00 = b01 = b02 = b10 = b11 = b12 = b20 = b21 = b22 = 0.0
            l00 = l01 = l02 = l10 = l11 = l12 = l20 = l21 = l22 = 0.0
            for k in range(S):
                dz = (k - fz) * h[2]
                for j in range(S):
                    dy = (j - fy) * h[1]
                    row = (iy + j) * strides[1] + (iz + k) * strides[2] - offset
                    wyz, gyz, wygz = wy[j] * wz[k], gy[j] * wz[k], wy[j] * gz[k]
                    for i in range(S):
                        node = row + ix + i   # (strides[0] is 1: x fastest)
                        w = wx[i] * wyz
                        vx, vy, vz = v_new[node, 0], v_new[node, 1], v_new[node, 2]
                        if mode != KINEMATICS:
                            vpx += w * vx
                            vpy += w * vy
                            vpz += w * vz
                            if blend:
                                dvx += w * (vx - v_old[node, 0])
                                dvy += w * (vy - v_old[node, 1])
                                dvz += w * (vz - v_old[node, 2])
                            if affine:
                                dx = (i - fx) * h[0]
                                b00 += vx * w * dx
                                b01 += vx * w * dy
                                b02 += vx * w * dz
                                b10 += vy * w * dx
                                b11 += vy * w * dy
                                b12 += vy * w * dz
                                b20 += vz * w * dx
                                b21 += vz * w * dy
                                b22 += vz * w * dz
                        if mode != REMAP:
                            dwx = gx[i] * wyz
                            dwy = wx[i] * gyz
                            dwz = wx[i] * wygz
                            l00 += vx * dwx
                            l01 += vx * dwy
                            l02 += vx * dwz
                            l10 += vy * dwx
                            l11 += vy * dwy
                            l12 += vy * dwz
                            l20 += vz * dwx
                            l21 += vz * dwy
                            l22 += vz * dwz
            if mode != KINEMATICS:
                if blend:
                    v[p, 0] = flip * (v[p, 0] + dvx) + (1.0 - flip) * vpx
                    v[p, 1] = flip * (v[p, 1] + dvy) + (1.0 - flip) * vpy
                else:
                    v[p, 0], v[p, 1] = vpx, vpy
                v[p, 2] = flip * (v[p, 2] + dvz) + (1.0 - flip) * vpz
                if affine:
                    C[p, 0, 0], C[p, 0, 1], C[p, 0, 2] = b00 * d_inv0, b01 * d_inv1, b02 * d_inv2
                    C[p, 1, 0], C[p, 1, 1], C[p, 1, 2] = b10 * d_inv0, b11 * d_inv1, b12 * d_inv2
                    C[p, 2, 0], C[p, 2, 1], C[p, 2, 2] = b20 * d_inv0, b21 * d_inv1, b22 * d_inv2
            if mode == REMAP:
                rate[p, 0], rate[p, 1], rate[p, 2] = vpx, vpy, vpz
                m = mass[p]
                for k in range(S):
                    dz = (k - fz) * h[2]
                    for j in range(S):
                        dy = (j - fy) * h[1]
                        row = (iy + j) * strides[1] + (iz + k) * strides[2] - offset
                        for i in range(S):
                            node = row + ix + i   # (strides[0] is 1: x fastest)
                            mw = m * (wx[i] * (wy[j] * wz[k]))
                            px, py, pz = v[p, 0], v[p, 1], v[p, 2]
                            if affine:
                                dx = (i - fx) * h[0]
                                px += C[p, 0, 0] * dx + C[p, 0, 1] * dy + C[p, 0, 2] * dz
                                py += C[p, 1, 0] * dx + C[p, 1, 1] * dy + C[p, 1, 2] * dz
                                pz += C[p, 2, 0] * dx + C[p, 2, 1] * dy + C[p, 2, 2] * dz
                            gp[node, 0] += mw * px
                            gp[node, 1] += mw * py
                            gp[node, 2] += mw * pz
                continue
            if mode == USL:
                x[p, 0] += dt * vpx
                x[p, 1] += dt * vpy
                x[p, 2] += dt * vpz
            else:
                x[p, 0] += dt * rate[p, 0]
                x[p, 1] += dt * rate[p, 1]
                x[p, 2] += dt * rate[p, 2]
            L[p, 0, 0], L[p, 0, 1], L[p, 0, 2] = l00, l01, l02
            L[p, 1, 0], L[p, 1, 1], L[p, 1, 2] = l10, l11, l12
            L[p, 2, 0], L[p, 2, 1], L[p, 2, 2] = l20, l21, l22
            for b in range(3):   # F <- (I + dt L) F, column by column
                f0, f1, f2 = F[p, 0, b], F[p, 1, b], F[p, 2, b]
                F[p, 0, b] = f0 + dt * l00 * f0 + dt * l01 * f1 + dt * l02 * f2
                F[p, 1, b] = f1 + dt * l10 * f0 + dt * l11 * f1 + dt * l12 * f2
                F[p, 2, b] = f2 + dt * l20 * f0 + dt * l21 * f1 + dt * l22 * f2
            J = determinant(F[p])
            volume[p] = J * volume0[p]
            if J <= 0.0 and bad[t] < 0:
                bad[t] = p
    if remaps and copies_mom.shape[0] > 0:
        add_node_copies(grid_mom, copies_mom)
