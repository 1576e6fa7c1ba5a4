"""CPDI-R4 (review 3.6.2-3.6.3, eqs. 3.27-3.35; Sadeghirad et al. 2011), in 1D (CPDI-L2,
eq. 3.26), 2D and 3D.

A particle's domain is the box of side l0 = h / particles_per_cell per axis it had
when seeded (the same box as GIMP's, solver/shape/kernels/gimp.py), carried by F:
the parallelogram (parallelepiped) x_p + R xi, xi in [-1, 1]^d, R = F diag(l0 / 2)
(the columns of R are the review's half-length domain vectors r_i, eq. 3.27).
The weight of node I is the mean of the hat function over the domain with the hat
replaced by its interpolant on the corners x_c = x_p + R s_c (s_c in {-1, 1}^d):

    phi_I      = 2^-d sum_c N_I(x_c)                                   (eq. 3.32)
    grad phi_I = sum_c N_I(x_c) g_c,  g_c = 2^-d R^-T s_c              (eq. 3.32)

g_c is the mean over the domain of the gradient of the corner's multilinear
function (the review's 2D expression written for any d: the affine map makes the
mean of d/dxi_a of prod_b (1 + s_cb xi_b) / 2 equal to s_ca / 2^d). The weights
sum to 1 and the gradients to 0 (eq. 3.33); a linear field's gradient is
reproduced exactly.

The stencil holds S nodes per axis, as many as the largest domain needs: it starts
at 3 (the compact stencil: domains within two cells per axis), and when the weights
refuse a particle whose corners span more the step widens it for the rest of the
run to `support_needed` (solver/step/general.py), as far as the corners reach up to
the kernels' widest stencil (solver/kernels.py: 10 nodes per axis in 2D, 4 in 3D).
Each corner adds to the 2^d nodes of its own cell only (the sums of eq. 3.32), so
S is merely where those nodes are stored. S = 4 keeps the corners within the
particle's cell and its neighbours (the slabs' halo with several processes, which
stop the run there naming the particle: `failure`). A domain stretched over more
than two cells develops the holes of review 3.7 / spec E28 (a node inside it that
no corner's cell touches gets no weight); the stretched E7 vortex
(tests/verification/test_cpdi_ulmpm.py) measures what that costs. A corner
beyond a grid end is moved onto it (review 3.7: "GIMP/CPDI need ghost cells";
here, as GIMP's boxes are cut), so the weights keep their partition of unity at
walls, at the price of linear reproduction for that particle.
"""
from __future__ import annotations

import numpy as np
from solver.jit import njit, prange

from solver.shape.kernels import gimp
from solver.shape.kernels.gimp import LENGTH  # the seeded boxes: the domains at t = 0
from solver.kernels import invert
from solver.threads import block_bounds, first_of

SUPPORT = 4
COMPACT = 3   # the compact stencil's nodes per axis (solver/shape/registry.py: compact_support)
CORNERS = "domain_corners"   # Particles.extra (n, 4, 2): cpdi_q4's tracked corners, counter-clockwise
SQUARE = np.array([[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]])   # x1..x4 of review eq. 3.34


def prepare(scene, particles) -> None:
    """The seeded boxes (all), and the tracked corners (cpdi_q4, cpdi_tet4): the boxes' corners
    at t = 0 (cpdi_q4 counter-clockwise, cpdi_tet4 axis 0 fastest as `domain_corners`)."""
    gimp.prepare(scene, particles)
    name = scene.method.shape_function
    if name not in ("cpdi_q4", "cpdi_tet4") or CORNERS in particles.extra:   # (restored from a checkpoint)
        return
    length = particles.extra[LENGTH]
    if name == "cpdi_q4":
        corners = particles.require(CORNERS, (4, 2))
        corners[:] = particles.x[:, None, :] + 0.5 * length[:, None, :] * SQUARE[None]
    else:
        corners = particles.require(CORNERS, (8, 3))
        corners[:] = domain_corners(particles.x, length, np.broadcast_to(np.eye(3), (particles.count, 3, 3)))


def evaluate(spec, x, particles, grid, stencil, blocks) -> int:
    return weights(spec, x, particles.extra[LENGTH], particles.F, grid.lower, grid.inv_h, grid.cells, grid.strides,
                   stencil.idx, stencil.w, stencil.dw, blocks)


def evaluate_tracked(spec, x, particles, grid, stencil, blocks) -> int:
    """cpdi_q4 and cpdi_tet4: the tracked corners (4 in 2D, 8 in 3D)."""
    return weights_tracked(spec, x, particles.extra[CORNERS], grid.lower, grid.inv_h, grid.cells, grid.strides,
                           stencil.idx, stencil.w, stencil.dw, blocks)


def failure(x, particles, grid, index):
    """(quantity, detail) for a particle the weights refused whose centre is inside the
    grid (its domain is too large), None for one outside the grid."""
    s = (x[index] - grid.lower) * grid.inv_h
    if not np.all((s >= 0) & (s <= grid.cells)):
        return None
    if CORNERS in particles.extra:
        corners = particles.extra[CORNERS][index]
    else:
        corners = domain_corners(x[index:index + 1], particles.extra[LENGTH][index:index + 1],
                                 particles.F[index:index + 1])[0]
    extent = (corners.max(axis=0) - corners.min(axis=0)) * grid.inv_h
    return ("particle domain (cpdi)",
            f"spans {np.array2string(extent, precision=3)} cells per axis, more than the widest stencil holds: "
            "with several processes the cells next to the particle's own (the slabs' halo), on one the kernels' "
            "largest stencil (10 nodes per axis in 2D, 4 in 3D); seed more particles per cell (a domain is "
            "h / particles_per_cell stretched by F), or run on one process; a tracked (cpdi_q4, cpdi_tet4) "
            "domain may also have folded")


def domain_corners(x, length, F) -> np.ndarray:
    """(n, 2^d, d): the corners x_p + F diag(l0/2) s_c, s_c in {-1, 1}^d with axis 0 fastest
    (2D: the review's x1, x2, x4, x3; the `particle_domain` output field)."""
    n, d = x.shape
    signs = np.array([[1.0 if (c >> a) & 1 else -1.0 for a in range(d)] for c in range(2 ** d)])
    R = F[:, :d, :d] * (0.5 * length)[:, None, :]
    return x[:, None, :] + np.einsum("pab,cb->pca", R, signs)


@njit(parallel=True, cache=True)
def weights(spec, x, length, F, lower, inv_h, cells, strides, idx, w, dw, blocks):
    """CPDI-R4: the domains carried by F (`length` the seeded box sides)."""
    dims, nodes = spec
    if _nodes_per_axis(len(nodes), len(dims)) ** len(dims) != len(nodes) or len(nodes) < COMPACT ** len(dims):
        raise ValueError("cpdi: the stencil is not S^d nodes, S >= 3")
    bounds = block_bounds(x.shape[0], blocks)
    bad = np.empty(blocks, dtype=np.int64)
    for t in prange(blocks):
        bad[t] = _carried_block(dims, nodes, bounds[t], bounds[t + 1], x, length, F, lower, inv_h, cells, strides,
                                idx, w, dw)
    return first_of(bad)


@njit(cache=True)
def _carried_block(dims, nodes, start, stop, x, length, F, lower, inv_h, cells, strides, idx, w, dw):
    dim = len(dims)
    corners = 2 ** dim
    base = np.empty(dim, dtype=np.int64)
    R = np.empty((dim, dim))        # the half-length domain vectors as columns, in cell units
    Rinv = np.empty((dim, dim))
    at = np.empty((corners, dim))   # the corners, in cells from the grid's lower end
    wf = np.full(corners, 1.0 / corners)
    gw = np.empty((corners, dim))   # the corners' gradient weights, per length
    cell, frac = np.empty((corners, dim), dtype=np.int64), np.empty((corners, dim))   # _scatter's scratch
    for p in range(start, stop):
        if not _first_nodes(p, x, lower, inv_h, cells, base):
            return p
        for a in range(dim):
            for b in range(dim):
                R[a, b] = F[p, a, b] * 0.5 * length[p, b] * inv_h[a]
        if invert(R, Rinv) <= 0.0:   # an inverted domain (the step reports its J)
            return p
        for c in range(corners):
            for a in range(dim):
                s = (x[p, a] - lower[a]) * inv_h[a]
                g = 0.0
                for b in range(dim):
                    sign = 1.0 if (c >> b) & 1 else -1.0
                    s += R[a, b] * sign
                    g += Rinv[b, a] * sign   # g_c = 2^-d R^-T s_c; R in cells: d/dx_a = inv_h[a] d/ds_a
                at[c, a] = s
                gw[c, a] = g * inv_h[a] / corners
        if not _scatter(p, nodes, base, at, wf, gw, cells, strides, idx, w, dw, cell, frac):
            return p
    return -1


@njit(cache=True)
def _first_nodes(p, x, lower, inv_h, cells, base):
    """The stencil's first node per axis: the node below the particle's cell (shifted
    inwards at the grid ends); False for a particle outside the grid (or NaN)."""
    for a in range(x.shape[1]):
        s = (x[p, a] - lower[a]) * inv_h[a]
        if not (s >= 0.0 and s <= cells[a]):
            return False
        base[a] = min(max(min(int(s), cells[a] - 1) - 1, 0), cells[a] - 3)
    return True


@njit(cache=True)
def _scatter(p, nodes, base, at, wf, gw, cells, strides, idx, w, dw, cell, frac):
    """phi_I = sum_c wf_c N_I(x_c) and grad phi_I = sum_c gw_c N_I(x_c), the corners `at` (in
    cells) moved onto the grid, on a stencil of S nodes per axis (`nodes` S^d long). S = SUPPORT
    (4): from `base`, the node below the particle's cell; False where a corner lies outside the
    particle's cell and its two neighbours per axis (the slabs' halo, solver/parallel). Any other
    S (3, the compact stencil; 5 and more, stretched domains): the nodes of the S - 1 cells per
    axis from the corners' lowest; False where the corners span more (the step then widens the
    stencil to what the largest domain needs: `support_needed`). Either way the nonzero entries
    come in the same order (node by node, axis 0 fastest), so every S gives the same sums.
    cell (2^d, d) int64, frac (2^d, d): scratch, allocated once per block by the caller."""
    corners, dim = at.shape
    span = _nodes_per_axis(len(nodes), dim)   # (len(nodes) is a compile-time constant)
    for c in range(corners):
        for a in range(dim):   # the corner's cell and its position in it
            s = min(max(at[c, a], 0.0), float(cells[a]))
            i = min(int(s), cells[a] - 1)
            cell[c, a] = i
            frac[c, a] = s - i
    if span != SUPPORT:
        for a in range(dim):
            low = cell[0, a]
            for c in range(1, corners):
                low = min(low, cell[c, a])
            base[a] = max(min(low, cells[a] - span + 1), 0)   # (0: a grid of fewer cells than the stencil)
    for c in range(corners):
        for a in range(dim):
            if cell[c, a] < base[a] or cell[c, a] > base[a] + span - 2:
                return False
    _clear(p, span, base, cells, strides, idx, w, dw)
    for c in range(corners):
        for j in range(2 ** dim):   # the 2^d nodes of the corner's cell
            k = 0
            stride = 1
            N = 1.0
            for a in range(dim):
                bit = (j >> a) & 1
                k += (cell[c, a] - base[a] + bit) * stride
                stride *= span
                N *= frac[c, a] if bit else 1.0 - frac[c, a]
            w[p, k] += N * wf[c]
            for a in range(dim):
                dw[p, k, a] += N * gw[c, a]
    return True


@njit(cache=True)
def _nodes_per_axis(nodes, dim):
    """S with S^dim = nodes."""
    span = 1
    while span ** dim < nodes:
        span += 1
    return span


@njit(cache=True)
def _clear(p, span, base, cells, strides, idx, w, dw):
    """Particle p's stencil: node k = sum_a (base_a + k_a) strides_a (k_a the digits of k in base
    `span`, axis 0 fastest), zero weights. A node beyond a grid end (a grid of fewer cells per
    axis than the stencil) is numbered as the last one: its entry keeps weight 0."""
    dim = base.shape[0]
    k = 0
    for k2 in range(span if dim > 2 else 1):
        for k1 in range(span if dim > 1 else 1):
            for k0 in range(span):
                node = min(base[0] + k0, cells[0]) * strides[0]
                if dim > 1:
                    node += min(base[1] + k1, cells[1]) * strides[1]
                if dim > 2:
                    node += min(base[2] + k2, cells[2]) * strides[2]
                idx[p, k] = node
                w[p, k] = 0.0
                for a in range(dim):
                    dw[p, k, a] = 0.0
                k += 1


def support_needed(x, particles, grid) -> int:
    """The nodes per axis a stencil needs to hold every particle's domain (the largest number
    of cells per axis its corners span, plus one): what the step widens to when the weights
    refuse a particle (solver/step/general.py)."""
    if CORNERS in particles.extra:
        corners = particles.extra[CORNERS]
    else:
        corners = domain_corners(x, particles.extra[LENGTH], particles.F)
    cells = np.asarray(grid.cells)
    s = np.clip((corners - grid.lower) * grid.inv_h, 0.0, cells)
    cell = np.minimum(np.floor(np.nan_to_num(s)), cells - 1)
    return int((cell.max(axis=1) - cell.min(axis=1)).max(initial=0)) + 2


# --------------------------------------------------------------------------- CPDI-Q4

@njit(cache=True)
def _scatter_corners(p, nodes, base, q, lower, inv_h, at, wf, gw, cells, strides, idx, w, dw, cell, frac):
    """_scatter with the tracked corners q (2^d, d) in cells from the grid's lower end (`at`)."""
    for c in range(q.shape[0]):
        for d in range(q.shape[1]):
            at[c, d] = (q[c, d] - lower[d]) * inv_h[d]
    return _scatter(p, nodes, base, at, wf, gw, cells, strides, idx, w, dw, cell, frac)


@njit(parallel=True, cache=True)
def weights_tracked(spec, x, corners, lower, inv_h, cells, strides, idx, w, dw, blocks):
    """CPDI-Q4 (review eqs. 3.36-3.37, the sign of eq. 3.37 corrected as the spec says): the
    weights of a quadrilateral from its four tracked corners; CPDI-Tet4 (3D): of the
    hexahedron of eight, as six tetrahedra (below)."""
    dims, nodes = spec
    dim = len(dims)
    if (_nodes_per_axis(len(nodes), dim) ** dim != len(nodes) or len(nodes) < COMPACT ** dim
            or corners.shape[1] != 2 ** dim or dim == 1):
        raise ValueError("cpdi_q4 / cpdi_tet4: 2D / 3D, S^d nodes (S >= 3), 2^d corners")
    bounds = block_bounds(x.shape[0], blocks)
    bad = np.empty(blocks, dtype=np.int64)
    for t in prange(blocks):
        if dim == 2:
            bad[t] = _tracked_block(nodes, bounds[t], bounds[t + 1], x, corners, lower, inv_h, cells, strides,
                                    idx, w, dw)
        else:
            bad[t] = _tetrahedra_block(nodes, bounds[t], bounds[t + 1], x, corners, lower, inv_h, cells, strides,
                                       idx, w, dw)
    return first_of(bad)


@njit(cache=True)
def _tracked_block(nodes, start, stop, x, corners, lower, inv_h, cells, strides, idx, w, dw):
    base = np.empty(2, dtype=np.int64)
    cell, frac = np.empty((4, 2), dtype=np.int64), np.empty((4, 2))   # _scatter's scratch
    at = np.empty((4, 2))
    wf = np.empty(4)
    gw = np.empty((4, 2))
    for p in range(start, stop):
        if not _first_nodes(p, x, lower, inv_h, cells, base):
            return p
        q = corners[p]
        x1, y1, x2, y2, x3, y3, x4, y4 = q[0, 0], q[0, 1], q[1, 0], q[1, 1], q[2, 0], q[2, 1], q[3, 0], q[3, 1]
        V = 0.5 * ((x1 * y2 - x2 * y1) + (x2 * y3 - x3 * y2) + (x3 * y4 - x4 * y3) + (x4 * y1 - x1 * y4))
        if not V > 0.0:      # folded or inverted quadrilateral (also NaN)
            return p
        a = (x4 - x1) * (y2 - y3) - (x2 - x3) * (y4 - y1)
        b = (x3 - x4) * (y1 - y2) - (x1 - x2) * (y3 - y4)
        wf[0], wf[1] = (6 * V - a - b) / (24 * V), (6 * V - a + b) / (24 * V)
        wf[2], wf[3] = (6 * V + a + b) / (24 * V), (6 * V + a - b) / (24 * V)
        gw[0, 0], gw[0, 1] = (y2 - y4) / (2 * V), (x4 - x2) / (2 * V)
        gw[1, 0], gw[1, 1] = (y3 - y1) / (2 * V), (x1 - x3) / (2 * V)
        gw[2, 0], gw[2, 1] = (y4 - y2) / (2 * V), (x2 - x4) / (2 * V)
        gw[3, 0], gw[3, 1] = (y1 - y3) / (2 * V), (x3 - x1) / (2 * V)
        if not _scatter_corners(p, nodes, base, q, lower, inv_h, at, wf, gw, cells, strides, idx, w, dw, cell,
                                frac):
            return p
    return -1


@njit(parallel=True, cache=True)
def move_corners(corners, x, v_grid, lower, inv_h, cells, strides, offset, dt, blocks):
    """Eq. 3.38: x_c += dt sum_I N_I(x_c) v_I, the hats at each corner (moved onto the grid);
    then the particle is put at its domain's centroid, sum_c wf_c x_c (eq. 3.39), so that
    particle and domain stay one (moved apart, the particle's stencil and its domain drift)."""
    bounds = block_bounds(corners.shape[0], blocks)
    for t in prange(blocks):
        first, frac, v = np.empty(2, dtype=np.int64), np.empty(2), np.empty(2)
        for p in range(bounds[t], bounds[t + 1]):
            for c in range(4):
                _move_corner(corners[p, c], v_grid, lower, inv_h, cells, strides, offset, dt, first, frac, v)
            _centroid(corners[p], x[p])


@njit(cache=True)
def _centroid(q, out):
    """The area centroid of the quadrilateral q (4, 2), from its two triangles 1-2-3 and 1-3-4."""
    ax, ay = q[1, 0] - q[0, 0], q[1, 1] - q[0, 1]
    bx, by = q[2, 0] - q[0, 0], q[2, 1] - q[0, 1]
    cx, cy = q[3, 0] - q[0, 0], q[3, 1] - q[0, 1]
    a1 = 0.5 * (ax * by - ay * bx)
    a2 = 0.5 * (bx * cy - by * cx)
    for d in range(2):
        out[d] = ((q[0, d] + q[1, d] + q[2, d]) * a1 + (q[0, d] + q[2, d] + q[3, d]) * a2) / (3.0 * (a1 + a2))


@njit(cache=True)
def _move_corner(corner, v_grid, lower, inv_h, cells, strides, offset, dt, first, frac, v):
    """x_c += dt sum_I N_I(x_c) v_I over the 2^d nodes of the corner's cell (moved onto the
    grid); first, frac, v: scratch arrays of length d (allocated once per block)."""
    dim = corner.shape[0]
    for a in range(dim):
        v[a] = 0.0
    for a in range(dim):
        s = min(max((corner[a] - lower[a]) * inv_h[a], 0.0), float(cells[a]))
        first[a] = min(int(s), cells[a] - 1)
        frac[a] = s - first[a]
    for j in range(2 ** dim):
        N = 1.0
        node = -offset
        for a in range(dim):
            bit = (j >> a) & 1
            N *= frac[a] if bit else 1.0 - frac[a]
            node += (first[a] + bit) * strides[a]
        for a in range(dim):
            v[a] += N * v_grid[node, a]
    for a in range(dim):
        corner[a] += dt * v[a]


class TrackedCorners:
    """cpdi_q4's and cpdi_tet4's hook (solver/step/hooks.py): the corners move with the grid
    velocity the particles just took (eq. 3.38; review Algorithm 5: at the end of every step)."""

    def __init__(self, move):
        self.move = move

    def after_g2p(self, sim, dt: float) -> None:
        f = sim.frame
        p = sim.particles
        self.move(p.extra[CORNERS], p.x, sim.grid.v_new, f.lower, f.inv_h, f.cells, f.strides, f.offset, dt,
                  sim.threads)


def hook(sim):
    return TrackedCorners(move_corners)


def hook_tetrahedra(sim):
    return TrackedCorners(move_corners_tetrahedra)


# --------------------------------------------------------------------------- CPDI-Tet4

# The Kuhn (Freudenthal) split of a hexahedron into six tetrahedra around its diagonal from
# corner 0 to corner 7 (corners numbered axis 0 fastest): tetrahedron {0, e_i, e_i + e_j, 7}
# for each order (i, j, k) of the axes, its middle vertices swapped for the odd orders so
# that every one is positively oriented. Every box of a lattice split this way shares its
# faces' triangles with its neighbours', so tracked domains tile the body as CPDI-Q4's do.
KUHN = np.array([[0, 1 << i, (1 << i) | (1 << j), 7] for i, j in ((0, 1), (1, 2), (2, 0))]
                + [[0, (1 << i) | (1 << j), 1 << i, 7] for i, j in ((0, 2), (1, 0), (2, 1))], dtype=np.int64)


@njit(cache=True)
def tetrahedra_weights(q, tets, wf, gw, centroid, J, Jinv):
    """The corner weights of the hexahedron q (8, 3) as the union of its tetrahedra: the
    domain average of the hats' piecewise-linear interpolant on the tetrahedra,
    wf_c = sum_t V_t / (4 V) [c in t] and gw_c = sum_t V_t / V grad lambda_c^t
    ([R] 3.6, CPDI-Tet4, eqs. 3.40-3.41 per tetrahedron, volume-averaged); `centroid`
    gets the domain's volume centroid (J, Jinv: 3 x 3 scratch). Returns V, or <= 0 where a
    tetrahedron folded."""
    for c in range(8):
        wf[c] = 0.0
        for a in range(3):
            gw[c, a] = 0.0
    for a in range(3):
        centroid[a] = 0.0
    total = 0.0
    for t in range(tets.shape[0]):
        v0 = tets[t, 0]
        for b in range(3):
            for a in range(3):
                J[a, b] = q[tets[t, b + 1], a] - q[v0, a]   # the edges from the first vertex as columns
        volume = invert(J, Jinv) / 6.0
        if not volume > 0.0:   # a folded tetrahedron (also NaN)
            return -1.0
        total += volume
        for a in range(3):
            g0 = 0.0
            for b in range(3):
                gw[tets[t, b + 1], a] += volume * Jinv[b, a]   # grad lambda_b = row b of J^-1
                g0 -= Jinv[b, a]
            gw[v0, a] += volume * g0
            centroid[a] += volume * 0.25 * (q[v0, a] + q[tets[t, 1], a] + q[tets[t, 2], a] + q[tets[t, 3], a])
        for b in range(4):
            wf[tets[t, b]] += 0.25 * volume
    for c in range(8):
        wf[c] /= total
        for a in range(3):
            gw[c, a] /= total
    for a in range(3):
        centroid[a] /= total
    return total


@njit(cache=True)
def _tetrahedra_block(nodes, start, stop, x, corners, lower, inv_h, cells, strides, idx, w, dw):
    base = np.empty(3, dtype=np.int64)
    cell, frac = np.empty((8, 3), dtype=np.int64), np.empty((8, 3))   # _scatter's scratch
    at = np.empty((8, 3))
    wf = np.empty(8)
    gw = np.empty((8, 3))
    centroid = np.empty(3)
    J, Jinv = np.empty((3, 3)), np.empty((3, 3))
    for p in range(start, stop):
        if not _first_nodes(p, x, lower, inv_h, cells, base):
            return p
        q = corners[p]
        if not tetrahedra_weights(q, KUHN, wf, gw, centroid, J, Jinv) > 0.0:
            return p
        if not _scatter_corners(p, nodes, base, q, lower, inv_h, at, wf, gw, cells, strides, idx, w, dw, cell,
                                frac):
            return p
    return -1


@njit(parallel=True, cache=True)
def move_corners_tetrahedra(corners, x, v_grid, lower, inv_h, cells, strides, offset, dt, blocks):
    """Eq. 3.38 for the eight corners, then the particle at its domain's volume centroid."""
    bounds = block_bounds(corners.shape[0], blocks)
    for t in prange(blocks):
        wf = np.empty(8)
        gw = np.empty((8, 3))
        centroid = np.empty(3)
        first, frac, v = np.empty(3, dtype=np.int64), np.empty(3), np.empty(3)
        J, Jinv = np.empty((3, 3)), np.empty((3, 3))
        for p in range(bounds[t], bounds[t + 1]):
            for c in range(8):
                _move_corner(corners[p, c], v_grid, lower, inv_h, cells, strides, offset, dt, first, frac, v)
            # a folded domain keeps its particle where it was: the next weights stop the run there
            if tetrahedra_weights(corners[p], KUHN, wf, gw, centroid, J, Jinv) > 0.0:
                x[p, :] = centroid
