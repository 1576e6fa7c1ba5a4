"""APIC: the affine particle-in-cell transfer (Jiang et al. 2015; review 5.5, eqs. 5.37-5.38).

Each particle carries, besides v_p, an affine velocity matrix C_p (dim x dim,
`Particles.extra["affine"]`), so that near the particle the velocity field it
represents is v_p + C_p (x - x_p). Both transfers keep that field:

- P2G adds m_p w_Ip C_p (x_I - x_p) to the momentum of node I (eq. 5.37);
- G2P sets v_p = sum_I w_Ip v_I (pure PIC) and C_p = B_p D_p^-1 with
  B_p = sum_I w_Ip v_I (x_I - x_p)^T and D_p = sum_I w_Ip (x_I - x_p)(x_I - x_p)^T (eq. 5.38).

The transfers then preserve linear and angular momentum exactly (Jiang et al.,
section 5), which PIC does not (it loses the rotation inside each stencil) and
FLIP only keeps by carrying the noise along.

D_p is diagonal for every tensor-product function that reproduces linear fields
(the cross terms factor into sum_j w_j (x_j - x_p) = 0 per axis), so it is
computed per axis and inverted as such: h^2/4 for quadratic and h^2/3 for cubic
B-splines in the interior, as Jiang et al. give, but the general sum also covers
GIMP, Bernstein and the boundary-modified cubic splines.

Not with linear hat functions (scene validation): there w_Ip D_p^-1 (x_I - x_p)
= grad w_Ip (Jiang et al.), so C_p = sum_I v~_I (x) grad w_Ip. On a node that a
particle barely touches, v~_I = v_I + dt f_I / m_I carries an acceleration of
order 1 / w_Ip (review 2.5.3, E24); PIC damps it by the weight w_Ip, but the hat
gradient does not vanish where the weight does, so C_p takes it undamped. MUSL
avoids this for L_p by remapping, which APIC cannot do without giving up the
conservation it exists for. Measured: the spinning disk of
tests/verification/test_apic.py inverts a particle within 15 steps, with the
general D_p and with the gradient form alike. C1 functions have grad w -> 0 as
w -> 0, which bounds the term.

MLS (Hu et al. 2018; review 5.5, spec A.12) is APIC whose weight gradient is the
moving-least-squares one, grad w_Ip ~ w_Ip D_p^-1 (x_I - x_p), wherever the step
uses a gradient: the stress enters P2G as f_I = -sum_p V_p sigma_p D_p^-1 w_Ip (x_I - x_p)
and the velocity gradient is L_p = sum_I v_I w_Ip (x_I - x_p)^T D_p^-1, which for USL
is C_p itself (the same v~_I^{t+dt}): one gather gives both. `MLSTransfer.gradients`
writes that gradient over the stored stencil's dw right after the weights, so every
kernel downstream (P2G force, kinematics, hoop terms) uses it unchanged; the fused
kernels form it inline (solver/fused_template.py). Its force is bounded by the weight
(f_I / m_I stays finite on a barely touched node) where grad w of a C0 function is
not; with a C1 function both vanish together, and only C1 ones are allowed (scene
validation, `ShapeFunction.smooth`).

The kernels take the positions the weights were evaluated at (x_p for ULMPM, the
reference X_p for TLMPM) and the node coordinates of the same grid, so TLMPM can
call them too.
"""
from __future__ import annotations

import numpy as np
from solver.jit import njit, prange

from solver.threads import add_node_copies, block_bounds, own

AFFINE = "affine"   # Particles.extra: (n, dim, dim) C_p


class AffineTransfer:
    """The APIC terms of one scene's transfers; the stepper calls these around its
    PIC kernels (flip_ratio 0)."""

    mls = False   # whether the step's weight gradients are MLS's (`gradients`)

    def __init__(self, particles, grid):
        particles.require(AFFINE, (grid.h.shape[0], grid.h.shape[0]))
        self.node_x = np.tile(grid.node_positions(), (grid.fields, 1))   # x_I of every field's nodes

    def gradients(self, spec, stencil, x, blocks: int) -> None:
        """APIC keeps the shape function's gradients."""

    def p2g(self, spec, stencil, particles, x, grid_mom, copies_mom) -> None:
        affine_p2g(spec, stencil.idx, stencil.w, particles.mass, x, particles.extra[AFFINE], self.node_x, grid_mom,
                   copies_mom)

    def g2p(self, spec, stencil, particles, x, v_grid, double_map: bool, grid_mom, copies_mom) -> None:
        """C_p from the grid velocities; with `double_map` (MUSL) also the affine part
        of the momentum mapped back to the grid (call before kernels.g2p moves x)."""
        affine_g2p(spec, stencil.idx, stencil.w, v_grid, x, particles.mass, self.node_x,
                   particles.extra[AFFINE], double_map, grid_mom, copies_mom)


class MLSTransfer(AffineTransfer):
    """APIC with the MLS gradient w_Ip D_p^-1 (x_I - x_p) in place of grad w_Ip."""

    mls = True

    def gradients(self, spec, stencil, x, blocks: int) -> None:
        """Overwrite the stencil's dw with the MLS gradient (after the weights are evaluated at x)."""
        mls_gradients(spec, stencil.idx, stencil.w, x, self.node_x, stencil.dw, blocks)


TRANSFERS = {"apic": AffineTransfer, "mls": MLSTransfer}   # the transfers that carry C_p


def affine_transfer(scene, particles, grid) -> AffineTransfer | None:
    """The affine transfer the scene's method names, placed on `grid`; None for PIC and FLIP."""
    kind = TRANSFERS.get(scene.method.transfer)
    return kind(particles, grid) if kind is not None else None


@njit(parallel=True, cache=True)
def mls_gradients(spec, idx, w, x, node_x, dw, blocks):
    """dw_Ip = w_Ip D_p^-1 (x_I - x_p), D_p = sum_I w_Ip (x_I - x_p)(x_I - x_p)^T taken
    diagonal, as in `affine_g2p` (exactly diagonal for the tensor-product B-splines)."""
    dims, nodes = spec
    bounds = block_bounds(w.shape[0], blocks)
    for t in prange(blocks):
        _mls_gradients_block(dims, nodes, bounds[t], bounds[t + 1], idx, w, x, node_x, dw)


@njit(cache=True)
def _mls_gradients_block(dims, nodes, start, stop, idx, w, x, node_x, dw):
    dim, nk = len(dims), len(nodes)
    D = np.empty(dim)
    for p in range(np.uint64(start), np.uint64(stop)):   # unsigned: no wrap-around test (docs/internals.md)
        D[:] = 0.0
        for k in range(nk):
            node = np.uint64(idx[p, k])
            for b in range(dim):
                d = node_x[node, b] - x[p, b]
                D[b] += w[p, k] * d * d
        for k in range(nk):
            node = np.uint64(idx[p, k])
            for b in range(dim):
                dw[p, k, b] = w[p, k] * (node_x[node, b] - x[p, b]) / D[b]


@njit(parallel=True, cache=True)
def affine_p2g(spec, idx, w, mass, x, C, node_x, grid_mom, copies_mom):
    """grid_mom_I += sum_p m_p w_Ip C_p (x_I - x_p); block t of particles adds into
    copies_mom[t - 1] (solver/kernels.py), so there are copies + 1 blocks."""
    dims, nodes = spec
    blocks = copies_mom.shape[0] + 1
    bounds = block_bounds(w.shape[0], blocks)
    for t in prange(blocks):
        gp = own(t, grid_mom, copies_mom)
        for p in range(np.uint64(bounds[t]), np.uint64(bounds[t + 1])):
            affine_p2g_one(p, dims, nodes, idx, w, mass, x, C, node_x, gp)
    if blocks > 1:
        add_node_copies(grid_mom, copies_mom)


@njit(parallel=True, cache=True)
def affine_g2p(spec, idx, w, v_grid, x, mass, node_x, C, double_map, grid_mom, copies_mom):
    """C_p = B_p D_p^-1 (D_p diagonal); with double_map also adds the new affine
    momentum m_p w_Ip C_p (x_I - x_p) to grid_mom."""
    dims, nodes = spec
    blocks = copies_mom.shape[0] + 1
    bounds = block_bounds(w.shape[0], blocks)
    for t in prange(blocks):
        gp = own(t, grid_mom, copies_mom) if double_map else grid_mom
        _affine_g2p_block(dims, nodes, bounds[t], bounds[t + 1], idx, w, v_grid, x, mass, node_x, C, double_map, gp)
    if double_map and blocks > 1:
        add_node_copies(grid_mom, copies_mom)


@njit(cache=True)
def _affine_g2p_block(dims, nodes, start, stop, idx, w, v_grid, x, mass, node_x, C, double_map, grid_mom):
    dim, nk = len(dims), len(nodes)
    B = np.empty((dim, dim))
    D = np.empty(dim)
    d = np.empty(dim)
    for p in range(np.uint64(start), np.uint64(stop)):
        B[:, :] = 0.0
        D[:] = 0.0
        for k in range(nk):
            node = np.uint64(idx[p, k])
            wk = w[p, k]
            for b in range(dim):
                d[b] = node_x[node, b] - x[p, b]
                D[b] += wk * d[b] * d[b]
            for a in range(dim):
                va = v_grid[node, a]
                for b in range(dim):
                    B[a, b] += va * wk * d[b]
        for a in range(dim):
            for b in range(dim):
                C[p, a, b] = B[a, b] / D[b]
        if double_map:
            affine_p2g_one(p, dims, nodes, idx, w, mass, x, C, node_x, grid_mom)


@njit(cache=True)
def affine_p2g_one(p, dims, nodes, idx, w, mass, x, C, node_x, grid_mom):
    dim, nk = len(dims), len(nodes)
    for k in range(nk):
        node = np.uint64(idx[p, k])
        mw = mass[p] * w[p, k]
        for a in range(dim):
            s = 0.0
            for b in range(dim):
                s += C[p, a, b] * (node_x[node, b] - x[p, b])
            grid_mom[node, a] += mw * s
