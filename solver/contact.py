"""Contact between bodies with Coulomb friction ([R] 5.1; Bardenhagen et al. 2000;
verification spec A.8): a velocity field per body, corrected where bodies meet.

With `"contact": {"model": "friction"}` the grid holds one field per body (solver/state.py:
node I of field f is entry f * n_nodes + I) and every particle's stencil points into its
body's field (`after_weights`), so P2G, the grid update, the conditions, G2P and the
kinematics run unchanged and give each body the single-field solution [R] (5.1). This hook
then corrects the fields where they meet:

- contact nodes: nodes where more than one field has particles (weight > 0) and the bodies'
  particles fill the node (sum_k sum_p V_p phi_I >= FILL of its volume, `_touching`);
- normals ([R] 5.12, or 5.9-5.11 with the corrected bounds of A.8): g_k = sum_p w_p grad phi_I(x_p)
  over the particles of body k, which points out of body k; the normal of body k against
  the others at the node is n_k = (g_k/|g_k| - g_o/|g_o|) normalised, g_o the sum of the others'
  unit normals. Two bodies so get exactly opposite normals, which makes the correction
  conserve momentum at the node (the review's Fig. 47b: non-collinear normals do not).
  Against a rigid body the normal is the rigid surface's alone ([R] 5.1.5: rigid particles
  define the contact nodes and the normal): a flat rigid floor has one normal also under a
  body's corners, where the average would tilt and brake the sliding;
- centre-of-mass velocity v_cm = sum m_k v_k / sum m_k ([R] 5.3); a rigid body's field
  ([R] 5.1.5) has infinite mass: v_cm is its prescribed velocity;
- approach test D = (v_k - v_cm) . n_k > 0 ([R] 5.2), else release: unchanged;
- Coulomb correction ([R] 5.6-5.7): v_k -= D n_k + mu' D t_k with t_k the unit relative
  tangential velocity and mu' = min(mu, |dv_t| / D): the friction never reverses the relative
  sliding (A.8's check), it stops it at most.

Which velocities are corrected (Remark 33): v~_I^{t+dt} (USL, MUSL, USF), and in MUSL also the
velocity remapped from the particles, from which the strain rate is taken, so that a body's
stress does not see the other's approach. The velocity v_I^t is left as the bodies' own:
FLIP adds v_I^{t+dt} - v_I^t, and a corrected v_I^t would let particles keep their approach
speed. The impulses m_k (v_k - v~_k) of two bodies at a node sum to zero (opposite normals,
one v_cm), so each correction conserves momentum; the remap's second correction only shapes
the strain rate (the particles' momentum came from the first).

Frictional walls (wall mode "friction") are the same correction against a field at rest whose
normal is the face's (`friction_wall`), applied by the grid conditions (solver/step/hooks.py).
"""
from __future__ import annotations

import math

import numpy as np
from solver.jit import njit, prange

from solver.threads import add_node_copies, block_bounds, own

AXES = "xyz"


# -- the fields ------------------------------------------------------------------

def domain_support(scene, support: int) -> int:
    """The stencil width the slabs' halo must cover (solver/parallel): the density-gradient
    normals spread a particle over its cell's neighbours too (S2, [R] 5.9), one more node
    layer on each side than the shape function's stencil."""
    if scene.contact.fields and scene.contact.normals == "density_gradient":
        return support + 2
    return support


@njit(parallel=True, cache=True)
def fields_and_normals(spec, idx, body, field_of_body, n_nodes, w, dw, mass, volume, presence, gradient,
                       copies_presence, copies_gradient):
    """Point each particle's stencil into its body's field (idx += field * n_nodes) and, in the
    same pass, presence_I += V_p phi_I (the volume the body's particles give the node) and
    gradient_I += w_p grad phi_I ([R] 5.12) with w_p the mass (a rigid particle, which carries
    none: its volume, only the direction of its field's normal counts), per field through the
    stencil (solver/kernels.py's P2G pattern: block t of particles into copy t - 1)."""
    dims, nodes = spec
    blocks = copies_presence.shape[0] + 1
    bounds = block_bounds(w.shape[0], blocks)
    for t in prange(blocks):
        _normals_block(dims, nodes, bounds[t], bounds[t + 1], idx, body, field_of_body, n_nodes, w, dw, mass,
                       volume, own(t, presence, copies_presence), own(t, gradient, copies_gradient))
    if blocks > 1:
        add_node_copies(presence, copies_presence)
        add_node_copies(gradient, copies_gradient)


@njit(cache=True)
def _normals_block(dims, nodes, start, stop, idx, body, field_of_body, n_nodes, w, dw, mass, volume, presence,
                   gradient):
    dim, nk = len(dims), len(nodes)
    for p in range(start, stop):
        shift = field_of_body[body[p]] * n_nodes
        m = mass[p] if mass[p] > 0.0 else volume[p]
        for k in range(nk):
            node = idx[p, k] + shift
            idx[p, k] = node
            presence[node] += volume[p] * w[p, k]
            for a in range(dim):
                gradient[node, a] += m * dw[p, k, a]


@njit(cache=True)
def quadratic_spline(d):
    """[R] (5.10) in cells, with the bounds of A.8's erratum: 3/4 - d^2 for |d| <= 1/2,
    (3/2 - |d|)^2 / 2 for 1/2 <= |d| <= 3/2."""
    d = abs(d)
    if d <= 0.5:
        return 0.75 - d * d
    if d <= 1.5:
        return 0.5 * (1.5 - d) * (1.5 - d)
    return 0.0


@njit(cache=True)
def cell_densities(x, body, field_of_body, weight, lower, inv_h, cells, strides, n_nodes, density):
    """rho_c = sum_p w_p S2(x_p - x_c) / V_e ([R] 5.9) per field, at the cell centres; held at
    each cell's lower-corner node (density is a nodal array, fields * n_nodes), so that the
    slabs' halo exchange sums and shares them as it does nodal sums. Serial (a scatter)."""
    dim = x.shape[1]
    volume = 1.0
    for a in range(dim):
        volume /= inv_h[a]
    base = np.empty(dim, dtype=np.int64)
    s = np.empty(dim)
    for p in range(x.shape[0]):
        for a in range(dim):
            s[a] = (x[p, a] - lower[a]) * inv_h[a] - 0.5   # in cells, from the first centre
            base[a] = int(math.floor(s[a] + 0.5)) - 1
        first = field_of_body[body[p]] * n_nodes
        for k in range(3**dim):
            value = weight[p] / volume
            node = first
            inside = True
            r = k
            for a in range(dim):
                c = base[a] + r % 3
                r //= 3
                if c < 0 or c >= cells[a]:
                    inside = False
                    break
                value *= quadratic_spline(s[a] - c)
                node += c * strides[a]
            if inside:
                density[node] += value


@njit(cache=True)
def density_normals(density, cells, inv_h, fields, n_nodes, strides, gradient):
    """n_I = sum_c grad phi_I(x_c) rho_c ([R] 5.11) over the cells holding node I, phi the linear
    hat: at a cell centre d phi/d x_a = +-(1/h_a) / 2^(dim-1); rho_c at the cell's lower-corner
    node (cell_densities)."""
    dim = cells.shape[0]
    n_cells = 1
    for a in range(dim):
        n_cells *= cells[a]
    scale = 1.0 / 2 ** (dim - 1)
    for f in range(fields):
        for c in range(n_cells):
            node0 = f * n_nodes
            r = c
            for a in range(dim):
                node0 += (r % cells[a]) * strides[a]
                r //= cells[a]
            rho = density[node0]
            if rho == 0.0:
                continue
            for corner in range(1 << dim):
                node = node0
                for a in range(dim):
                    node += ((corner >> a) & 1) * strides[a]
                for a in range(dim):
                    sign = 1.0 if (corner >> a) & 1 else -1.0
                    gradient[node, a] += sign * inv_h[a] * scale * rho


# -- the correction --------------------------------------------------------------

@njit(cache=True)
def _unit(vector, out, floor=0.0):
    """out = vector / |vector| (0 where |vector| <= floor); returns |vector|."""
    norm = 0.0
    for a in range(vector.shape[0]):
        norm += vector[a] * vector[a]
    norm = math.sqrt(norm)
    for a in range(vector.shape[0]):
        out[a] = vector[a] / norm if norm > floor else 0.0
    return norm


@njit(cache=True)
def coulomb(v, v_cm, n, mu, out):
    """[R] (5.6)-(5.7) on one field's velocity v against v_cm with the outward unit normal n:
    out = the corrected velocity. Returns (D, mu' D, |dv_t|): the normal approach speed
    (<= 0: release, out = v), the tangential speed friction took off, the relative sliding
    speed before it."""
    dim = v.shape[0]
    D = 0.0
    for a in range(dim):
        D += (v[a] - v_cm[a]) * n[a]
    if D <= 0.0:
        for a in range(dim):
            out[a] = v[a]
        return 0.0, 0.0, 0.0
    slide = 0.0
    for a in range(dim):
        out[a] = v[a] - v_cm[a] - D * n[a]   # the relative tangential velocity
        slide += out[a] * out[a]
    slide = math.sqrt(slide)
    stop = min(mu * D, slide)   # mu' D: friction stops the sliding at most
    for a in range(dim):
        t = out[a] / slide if slide > 0.0 else 0.0
        out[a] = v[a] - D * n[a] - stop * t
    return D, stop, slide


@njit(cache=True)
def _normal(k, node, n_nodes, mass, presence, unit, touching, others, n):
    """n = the outward normal of field k against the other fields at the node (their unit
    normals `unit`); returns the partner whose friction applies: the rigid field `touching`,
    else the heaviest other; -1 where there is no normal."""
    dim = n.shape[0]
    partner = touching
    heaviest = 0.0
    for a in range(dim):
        others[a] = 0.0
    for f in range(unit.shape[0]):
        ef = f * n_nodes + node
        if f == k or presence[ef] <= 0.0 or (touching >= 0 and f != touching):
            continue
        for a in range(dim):
            others[a] += unit[f, a]
        if touching < 0 and mass[ef] > heaviest:
            heaviest, partner = mass[ef], f
    for a in range(dim):   # against a rigid body its surface's normal alone ([R] 5.1.5)
        others[a] = -others[a] if touching >= 0 else unit[k, a] - others[a]
    if partner < 0 or _unit(others, n) == 0.0:   # (also inside a rigid body, away from its surface)
        return -1
    return partner


# Bodies touch at a node when their particles give it at least this share of its volume
# (sum_k sum_p V_p phi_I = the node's volume inside bodies that fill their cells).
FILL = 0.9


@njit(cache=True)
def _touching(presence, fields, n_nodes, node, volume):
    """Whether the bodies' particles fill the node's volume (FILL of it): the bodies meet there.
    Velocities alone would see contact as soon as two bodies share a node, up to a cell (wide
    shape functions: two) before their particles meet, and the correction then acts on nodes
    one body barely reaches, whose velocity is f / m of a sliver of mass: head-on impacts of
    flat faces gained 10 % and more of their energy (docs/benchmarks.md). The volume check
    follows Nairn's contact detection (Nairn 2013, CB-Geo's friction contact)."""
    filled = 0.0
    for f in range(fields):
        filled += presence[f * n_nodes + node]
    return filled >= FILL * volume


@njit(cache=True)
def mark_touching(presence, fields, n_nodes, node_volume, touching):
    """touching[I] = whether node I is a contact node: more than one field has particles there
    and they fill it (the test correct_fields applies). Where the heat crosses (solver/thermal.py)."""
    for node in range(n_nodes):
        present = 0
        for f in range(fields):
            if presence[f * n_nodes + node] > 0.0:
                present += 1
        touching[node] = present >= 2 and _touching(presence, fields, n_nodes, node, node_volume[node])


@njit(cache=True)
def correct_fields(n_nodes, mass, presence, gradient, v, rigid, rigid_velocity, friction, flat, record, owned,
                   node_volume, impulse, pair_impulse, totals, heat):
    """Contact at every node where more than one field has particles (see the module docstring).

    mass, presence (fields * n_nodes,: the volume each body gives a node), gradient, v
    (fields * n_nodes, dim); node_volume (n_nodes,); rigid (fields,) bool
    and rigid_velocity (fields, dim) of the rigid bodies' fields; friction (fields, fields).
    A field has no normal at a node where |gradient| <= flat * its weight there (the mass, a
    rigid body's volume): inside a body, where
    the particles around the node balance (flat = 1e-9 / h: round-off; wide shape functions reach
    a cell or more into a rigid body, where its normal would be noise): no contact there.
    With `record`, on the nodes this process owns (`owned`; ghost copies are corrected alike and
    then overwritten by their owners' values): impulse[r] += m_k (v_k - v~_k) for a rigid field r (its action on the
    material), pair_impulse[k, o] += (normal, tangential) impulse of field o on field k,
    totals[0] += the rigid fields' work (impulse . v_r), totals[1] += the friction's work on the
    remaining sliding, -m_k mu'D (|dv_t| - mu'D) <= 0, and heat[e] (fields * n_nodes, or empty
    without conduction) += that work's heat at the node e of field k (solver/thermal.py).
    Serial: the nodes are independent but the sums are shared, and the loop is a small part
    of the step.
    """
    fields = rigid.shape[0]
    dim = v.shape[1]
    unit = np.zeros((fields, dim))
    others = np.empty(dim)
    n = np.empty(dim)
    v_cm = np.empty(dim)
    out = np.empty(dim)
    for node in range(n_nodes):
        present = 0
        touching = -1   # the rigid field at the node, if any (the first)
        for f in range(fields):
            if presence[f * n_nodes + node] > 0.0:
                present += 1
                if rigid[f] and touching < 0:
                    touching = f
        if present < 2 or not _touching(presence, fields, n_nodes, node, node_volume[node]):
            continue
        total = 0.0
        for a in range(dim):
            v_cm[a] = 0.0
        for f in range(fields):
            e = f * n_nodes + node
            if presence[e] > 0.0:
                _unit(gradient[e], unit[f], flat * (mass[e] if mass[e] > 0.0 else presence[e]))
                m = mass[e]
                total += m
                for a in range(dim):
                    v_cm[a] += m * v[e, a]
        for a in range(dim):
            v_cm[a] = rigid_velocity[touching, a] if touching >= 0 else (v_cm[a] / total if total > 0.0 else 0.0)
        for k in range(fields):
            e = k * n_nodes + node
            m = mass[e]
            if rigid[k] or presence[e] <= 0.0 or m <= 0.0:
                continue
            partner = _normal(k, node, n_nodes, mass, presence, unit, touching, others, n)
            if partner < 0:
                continue
            D, stop, slide = coulomb(v[e], v_cm, n, friction[k, partner], out)
            if D <= 0.0:
                continue
            if record and owned[node]:
                for a in range(dim):
                    j = m * (out[a] - v[e, a])
                    if touching >= 0:
                        impulse[touching, a] += j
                        totals[0] += j * v_cm[a]
                pair_impulse[k, partner, 0] += m * D
                pair_impulse[k, partner, 1] += m * stop
                totals[1] -= m * stop * (slide - stop)
                if heat.shape[0] > 0:
                    heat[e] += m * stop * (slide - stop)
            for a in range(dim):
                v[e, a] = out[a]


@njit(cache=True)
def friction_wall(node, axis, sign, mu, v, grid_mass, dissipated, heat):
    """Frictional walls at rest ([R] 5.1.5 with v_cm = 0 and the face's outward normal): a node
    moving into the wall loses that speed, and its sliding speed loses mu times it, at most
    all. dissipated[0] += the friction's work on the remaining sliding (<= 0), and heat[I]
    (empty without conduction) += that work's heat at the node."""
    dim = v.shape[1]
    n = np.zeros(dim)
    rest = np.zeros(dim)
    out = np.empty(dim)
    for i in range(node.shape[0]):
        I = node[i]
        n[:] = 0.0
        n[axis[i]] = sign[i]
        D, stop, slide = coulomb(v[I], rest, n, mu[i], out)
        if D > 0.0:
            dissipated[0] -= grid_mass[I] * stop * (slide - stop)
            if heat.shape[0] > 0:
                heat[I] += grid_mass[I] * stop * (slide - stop)
            for a in range(dim):
                v[I, a] = out[a]


# -- the hook ----------------------------------------------------------------------

def friction_matrix(scene) -> np.ndarray:
    """mu of every pair of fields (bodies): the contact's `friction`, overridden by `pairs`."""
    names = {body.name: b for b, body in enumerate(scene.bodies)}
    mu = np.full((len(names), len(names)), float(scene.contact.friction))
    for pair in scene.contact.pairs:
        a, b = (names[name] for name in pair.bodies)
        mu[a, b] = mu[b, a] = pair.friction
    return mu


def node_volumes(grid, axisymmetric: bool) -> np.ndarray:
    """The volume each node stands for: prod h (axisymmetric: times 2 pi r_I, as the particles'
    ring volumes; 0 on the axis, where the fill check then always passes)."""
    volume = np.full(grid.n_nodes, float(np.prod(grid.h)))
    if axisymmetric:
        volume *= 2.0 * np.pi * grid.node_positions()[:, 0]
    return volume


class FieldContact:
    """The contact of a scene with a velocity field per body, as a hook (solver/step/hooks.py):
    stencils into the fields and their normals (after_weights), the correction (constrain),
    and the per-pair force series."""

    def __init__(self, sim):
        scene, grid = sim.scene, sim.grid
        self.sim, self.grid = sim, grid
        self.normals = scene.contact.normals
        self.friction = friction_matrix(scene)
        self.rigid = np.ascontiguousarray(sim.rigid.is_rigid)
        self.field_of_body = np.arange(len(scene.bodies), dtype=np.int64)
        size, dim = grid.mass.shape[0], scene.dimension
        self.presence = np.zeros(size)
        self.gradient = np.zeros((size, dim))
        # the fused P2G scatters presence and gradient itself, into copies of its own (the grid's
        # copies are in use then); the general pass borrows the grid's (solver/step/fused.py)
        copies = sim.threads - 1 if sim.phases.carries_contact else 0
        self.copies_presence = np.zeros((copies, size))
        self.copies_gradient = np.zeros((copies, size, dim))
        self.impulse = sim.rigid.impulse   # the rigid bodies' reactions come from the contact
        self.pair_impulse = np.zeros((grid.fields, grid.fields, 2))
        self.owned = sim.domain.owned_mask(grid)
        self.flat = 1e-9 / float(np.min(grid.h))   # a normal below flat * weight is round-off
        self.node_volume = node_volumes(grid, scene.axisymmetric)
        self.totals = np.zeros(2)   # rigid fields' work, friction's work (this step)
        self._elapsed = 0.0
        self._dt = 0.0
        self.names = [b.name.replace("/", "_") for b in scene.bodies]
        self.pairs = [(a, b) for a in range(grid.fields) for b in range(a + 1, grid.fields)
                      if not (self.rigid[a] and self.rigid[b])]

    def after_weights(self, sim) -> None:
        """Stencils into the fields; the volume each field gives the nodes, and the fields' normals
        from the particles' weights w_p (the mass; a rigid particle, which carries none, its
        volume: only the direction of its field's normal counts). Once a step, before any grid
        velocity is formed. On the fused backend its P2G does both (`after_forces` sums the ghosts)."""
        if sim.phases.carries_contact:
            return
        p, s, g = sim.particles, sim.stencil, self.grid
        self.presence.fill(0.0)
        self.gradient.fill(0.0)
        fields_and_normals(sim.spec, s.idx, p.body, self.field_of_body, g.n_nodes, s.w, s.dw, p.mass, p.volume,
                           self.presence, self.gradient, sim.copies.mass, sim.copies.force)
        if self.normals == "density_gradient":
            self._density_normals(sim)
        sim.domain.sum_ghosts(self.presence, self.gradient)

    def _density_normals(self, sim) -> None:
        """[R] 5.9-5.11: the cell densities summed over the slabs and shared back (a cell's
        particles may sit on a neighbour's slab: `domain_support` widened the halo by the
        spline's reach), the normals from them on every node, kept on the owned ones only:
        the caller's sum over the slabs then adds nothing twice."""
        p, g = sim.particles, self.grid
        weight = np.where(p.mass > 0.0, p.mass, p.volume)
        self.gradient.fill(0.0)
        density = np.zeros(g.fields * g.n_nodes)
        cell_densities(p.x, p.body, self.field_of_body, weight, g.lower, g.inv_h, g.cells, g.strides, g.n_nodes,
                       density)
        sim.domain.sum_ghosts(density)
        sim.domain.share_nodes(density)
        density_normals(density, g.cells, g.inv_h, g.fields, g.n_nodes, g.strides, self.gradient)
        if not self.owned.all():
            for rows in g.field_views(self.gradient):
                rows[~self.owned] = 0.0

    def after_forces(self, sim) -> None:
        """The fused P2G's presence and normals, summed onto their owners (processes)."""
        if sim.phases.carries_contact:
            sim.domain.sum_ghosts(self.presence, self.gradient)

    def before_update(self, sim, dt: float) -> None:
        self._dt = dt

    def touching(self, out: np.ndarray) -> np.ndarray:
        """out[I] = whether the bodies touch at node I this step (after_weights has run), for the
        heat exchange (solver/thermal.py)."""
        mark_touching(self.presence, self.grid.fields, self.grid.n_nodes, self.node_volume, out)
        return out

    def constrain(self, grid_mass, v, record: bool) -> float:
        """Correct v~_I^{t+dt} and MUSL's remapped velocity; v_I^t stays the bodies' own (FLIP adds
        v_I^{t+dt} - v_I^t to the particles; USF takes its strain rate from it, as [R] Algorithm 6)."""
        if v is self.grid.v_old:
            return 0.0
        self.totals[:] = 0.0
        correct_fields(self.grid.n_nodes, grid_mass, self.presence, self.gradient, v, self.rigid,
                       self.sim.rigid.velocity, self.friction, self.flat, record, self.owned, self.node_volume,
                       self.impulse, self.pair_impulse, self.totals, self.sim.friction_heat)
        if record:
            self.sim.work.add("friction_work", float(self.totals[1]))
            self._elapsed += self._dt
        return float(self.totals[0])

    def series(self) -> dict[str, float]:
        """contact_<a>_<b>_normal / _tangential: the mean force of body b on body a since the last
        call (a deformable body first), normal and tangential magnitudes."""
        total = self.sim.domain.sum(self.pair_impulse)
        scale = 1.0 / self._elapsed if self._elapsed > 0 else 0.0
        out = {}
        for a, b in self.pairs:
            k, o = (b, a) if self.rigid[a] else (a, b)
            for c, part in enumerate(("normal", "tangential")):
                out[f"contact_{self.names[k]}_{self.names[o]}_{part}"] = float(total[k, o, c]) * scale
        self.pair_impulse[:] = 0.0
        self._elapsed = 0.0
        return out
