"""The fused backend: the weights are recomputed inside each transfer instead of
stored (solver/fused.py), for the scenes most runs are (`supports`): ULMPM with
linear hats or quadratic B-splines, USL or MUSL, PIC/FLIP/APIC, no hook that needs a
stored stencil. USL's G2P and kinematics are one pass; MUSL's remap keeps v_pic
(`rate`) until the kinematics pass moves x_p.

Heat conduction (MUSL only, fused_scope) rides in the same passes, in kernels generated
for conducting scenes alone: P2G adds C_I, (C T)_I, Q_I; the REMAP pass updates T_p and
maps m c T_p back; the KINEMATICS pass, after the conduction hook formed the remapped
T_I^{t+dt}, gathers q_p. The hook (solver/thermal.py) keeps the node passes.

Contact with a field per body (mass-gradient normals, fused_scope) rides in kernels generated
for it: every pass shifts each particle's nodes into its body's field, and P2G scatters the
contact's presence and normals too; the hook (solver/contact.py) keeps the correction."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from solver import fused, kernels, near_one_log, shape
from solver.kernels import rows_equal
from solver.threads import first_of
from solver.step.phases import Phases


# What a plan may be told to leave out (`FusedPhases.replan(without=...)`: the tests and
# benchmarks that hold a choice to the step without it).
CHOICES = ("fold", "forms_stress", "updates_stress", "p2g_mls", "g2p_mls", "g2p_kinematics", "lanes")


@dataclass(frozen=True)
class FusedPlan:
    """What the fused backend runs for its scene and hooks: chosen when the particles are placed
    and again when a hook is added (`FusedPhases.replan`); a step only reads it. The kernels that
    take flat views (p2g_mls, p2g_mls_lanes, g2p_mls, g2p_kinematics) fall back to p2g or g2p at a
    call where an array they view is not C-contiguous."""
    fold: bool             # P2G adds dt f_I into (mv)_I and forms no f_I (`_folds_force`)
    forms_stress: bool     # P2G forms sigma_p; the stress pass waits until it is read (`_forms_stress`)
    updates_stress: bool   # the pass that forms L_p updates sigma_p too (`_updates_stress`)
    l_is_c: bool           # USL's MLS gather leaves L_p = C_p, copied only where read
    p2g: str               # p2g_mls, p2g_mls_lanes, p2g_lanes or p2g
    g2p_usl: str           # USL's pass: g2p_mls, g2p_lanes or g2p
    g2p_kinematics: str    # MUSL's KINEMATICS pass: g2p_kinematics or g2p

    def makes(self, choice: str) -> bool:
        """Whether the plan makes `choice` (one of CHOICES)."""
        kernels = {"p2g_mls": self.p2g.startswith("p2g_mls"), "g2p_mls": self.g2p_usl == "g2p_mls",
                   "g2p_kinematics": self.g2p_kinematics == "g2p_kinematics",
                   "lanes": "lanes" in self.p2g or "lanes" in self.g2p_usl}
        return kernels[choice] if choice in kernels else getattr(self, choice)


class FusedPhases(Phases):
    name = "fused"
    carries_conduction = True   # the conduction hook leaves its particle passes to these kernels
    carries_contact = True      # the contact hook leaves its stencil shift and normals to them

    def __init__(self, sim):
        super().__init__(sim)
        self._without = frozenset()   # the plan's choices left out (`replan`), kept across placements

    @staticmethod
    def supports(scene) -> bool:
        return fused.supports(scene)

    def place_particles(self) -> None:
        sim = self.sim
        sim.stencil = None
        sim.rate = np.zeros((sim.particles.count, sim.scene.dimension))
        sim.formulation.place_particles(sim.particles)
        method = sim.scene.method
        self._support = fused.support_of(method.shape_function)
        model = self._stress_model = _stress_model(sim)
        # (asked at every step: looked up once, the class walk cost 1 % of mpm88's step at two threads)
        self._has_stress_lines = has_lines(model, "stress_lines")
        self._has_update_lines = has_lines(model, "stress_update_lines")
        self._kernels = fused.kernels(sim.scene.dimension, thermal=sim.conduction is not None,
                                      contact=sim.field_contact is not None,
                                      stress=_material_lines(sim, model, "stress_lines"),
                                      update=_material_lines(sim, model, "stress_update_lines"))
        apic_d = shape.REGISTRY[method.shape_function].apic_d
        # APIC's (and MLS's) D_p^-1 per axis (unused without them); placed with the particles, after the grid
        self._d_inv = fused.inverse_d(apic_d, sim.frame.inv_h) if sim.affine is not None else sim.frame.inv_h
        self._place_arguments()
        self.plan = self._plan(self._without)

    def _place_arguments(self) -> None:
        """What the kernels take that changes only when the grid or the particles are placed:
        built once here, not at every call (on a few hundred particles the tuples, the
        placeholder and the flags cost a tenth of a step)."""
        sim = self.sim
        dim = sim.scene.dimension
        f = sim.frame
        self._frame = (f.lower, f.h, f.inv_h, f.cells, f.strides, f.offset)
        # C_p for APIC; a placeholder of the right type for the kernels otherwise
        apic = sim.affine is not None
        self._affine_matrix = sim.particles.extra["affine"] if apic else np.zeros((1, dim, dim))
        self._bad = np.empty(sim.threads, dtype=np.int64)   # each block's first failing particle
        affine, blend = fused.constant(apic), fused.constant(sim.flip_ratio > 0.0)
        mls = fused.constant(apic and sim.affine.mls)
        self._p2g_variants = {(fold, inline): (self._support, affine, fused.constant(sim.loads.any), mls,
                                               fused.constant(fold), fused.constant(inline))
                              for fold in (False, True) for inline in (False, True)}
        model = self._stress_model
        self._stress_parameters = model.stress_parameters() if model is not None else np.zeros(0)
        # MLS's USL pass as `g2p_mls` (2D, no conduction or contact: the modules that have it; no FLIP blend)
        self._has_g2p_mls = hasattr(self._kernels, "g2p_mls") and sim.flip_ratio == 0.0
        # MLS's folded P2G as `p2g_mls` (the same modules; quadratic B-splines), log J vectorised where
        # log_near_one is libm's log in this process (else the kernel calls math.log)
        self._has_p2g_mls = (hasattr(self._kernels, "p2g_mls") and apic and sim.affine.mls
                             and self._support.ndim - 1 == 3)
        vector_log = fused.constant(self._has_p2g_mls and near_one_log.matches_libm())
        self._p2g_mls_variants = {(inline, shared): (fused.constant(sim.loads.any), fused.constant(inline), vector_log,
                                                     fused.constant(shared))
                                  for inline in (False, True) for shared in (False, True)}
        # MLS in 3D as `p2g_lanes` and `g2p_lanes`, in 2D `p2g_mls` as `p2g_mls_lanes`: a node's values
        # in four lanes (the modules that have them)
        lanes = hasattr(self._kernels, "p2g_lanes") or hasattr(self._kernels, "p2g_mls_lanes")
        self._has_lanes = lanes and apic and sim.affine.mls and sim.flip_ratio == 0.0 and self._support.ndim - 1 == 3
        self._has_p2g_lanes = self._has_lanes and hasattr(self._kernels, "p2g_lanes")   # (3D's: not in 2D)
        self._has_g2p_lanes = self._has_lanes and hasattr(self._kernels, "g2p_lanes")
        self._node_lanes = self._velocity_lanes = np.zeros((0, 0, 4))
        # MUSL's KINEMATICS pass as `g2p_kinematics` (the same modules; not MLS, whose L_p is B_p D_p^-1)
        self._has_g2p_kinematics = (hasattr(self._kernels, "g2p_kinematics") and sim.scene.method.scheme == "musl"
                                    and not (apic and sim.affine.mls))
        self._g2p_variants = {(mode, l_is_c, updates): (self._support, fused.constant(mode), affine, blend, mls,
                                                        fused.constant(l_is_c), fused.constant(updates))
                              for mode in (fused.USL, fused.REMAP, fused.KINEMATICS) for l_is_c in (False, True)
                              for updates in (False, True)}

    def weights(self) -> None:
        """Nothing to store: every kernel evaluates the weights it needs."""

    # -- the plan ------------------------------------------------------------------------------

    def replan(self, without: tuple[str, ...] = ()) -> None:
        """Choose the plan again, leaving out the choices named in `without` (of CHOICES) from now
        on: the step without them, which tests and benchmarks compare with the plan's own."""
        unknown = set(without) - set(CHOICES)
        assert not unknown, f"not a choice of the fused plan: {sorted(unknown)}"
        self._without = frozenset(without)
        self.plan = self._plan(self._without)

    def hooks_changed(self) -> None:
        self.plan = self._plan(self._without)

    def _plan(self, without: frozenset) -> FusedPlan:
        sim = self.sim
        mls = sim.affine is not None and sim.affine.mls
        fold = "fold" not in without and self._folds_force()
        forms = "forms_stress" not in without and self._forms_stress()
        lanes = "lanes" not in without and self._has_lanes
        splits_kinematics = "g2p_kinematics" not in without and self._has_g2p_kinematics
        updates = "updates_stress" not in without and self._updates_stress(splits_kinematics)
        l_is_c = mls and forms
        if fold and self._has_p2g_mls and "p2g_mls" not in without:
            p2g = "p2g_mls_lanes" if lanes else "p2g_mls"
        else:
            p2g = "p2g_lanes" if fold and lanes and self._has_p2g_lanes else "p2g"
        gathers_c = l_is_c and not updates
        if gathers_c and self._has_g2p_mls and "g2p_mls" not in without:
            usl = "g2p_mls"
        else:
            usl = "g2p_lanes" if gathers_c and lanes and self._has_g2p_lanes else "g2p"
        kinematics = "g2p_kinematics" if splits_kinematics and not updates else "g2p"
        return FusedPlan(fold, forms, updates, l_is_c, p2g, usl, kinematics)

    def forms_stress(self) -> bool:
        return self.plan.forms_stress

    def updates_stress(self) -> bool:
        return self.plan.updates_stress

    def _folds_force(self) -> bool:
        """Whether P2G adds dt f_I into (mv)_I instead of forming f_I: with MLS (the force is
        w-weighted like the momentum) or APIC with quadratic B-splines, no FLIP blend and no hook
        that reads or adds to f_I or reads v_I^t (loads on nodes, damping, absorbing faces,
        conduction: after_forces and before_update; contact fields too, whose normals need the
        grad w a folded P2G does not form). v_I^t is then not formed: the grid update gives
        q_I / m_I for both v_I^t and v~_I^{t+dt}, which equals the unfolded step's to round-off
        except on nodes below the mass cut-off (1e-9 of the lightest particle's mass), where the
        unfolded step drops dt f_I / m_I. What such a node's dt f_I / m_I gives a particle is
        bounded: with MLS its weight in the gather is below 1e-9 (`git show 63f7e3a^:docs/benchmarks.md`,
        "Speed, third part"); with quadratic B-splines, at distance d (in cells) inside the stencil's edge,
        w ~ d^2 and grad w ~ d / h, so dt f_I / m_I ~ 1 / d and the gather's w v_I ~ d and grad w
        v_I ~ 1 stay finite ("thirteenth part" there). With linear hats grad w stays 1 / h as w ~ d -> 0,
        which is why solver/scene.py refuses APIC with them."""
        sim = self.sim
        quadratic = sim.scene.method.shape_function == "quadratic_bspline"
        return (sim.affine is not None and (sim.affine.mls or quadratic) and sim.flip_ratio == 0.0
                and not sim.hooks.after_forces and not sim.hooks.before_update)

    def _forms_stress(self) -> bool:
        """Whether P2G forms sigma_p itself, so that the stress pass can wait until something
        reads the stress (Particles.defer): for a scene of one material whose stress is a
        function of what P2G can read (a model with `stress_lines`: neo-Hookean from F_p, the
        fluid from L_p and V_p / V0_p), when no hook changes the stress after the update (thermal
        expansion, F-bar), and, for a model whose wave speed comes with its stress update (the
        fluid), at a fixed time step: the CFL step would run the pass at every step anyway. The
        stress the pass would store is used to the bit with MPM_FMA=0 (to round-off with FMA
        contraction, the default: solver/fused_template.py CONTRACT), one pass over the particles
        and the stress's writes and reads less."""
        model = self._stress_model
        return (self._has_stress_lines and not self.sim.hooks.after_stress
                and (self.sim.scene.time.dt is not None or not getattr(model, "stress_sets_wave_speed", False)))

    def _updates_stress(self, splits_kinematics: bool) -> bool:
        """Whether G2P updates sigma_p from the L_p it has just formed (USL's pass, MUSL's
        KINEMATICS pass), so that the stress pass has nothing left to do: for a scene of one
        material whose update is a function of L_p and the stress (a model with
        `stress_update_lines`: linear elasticity), when no hook runs between the kinematics and
        the stress update or after it (after_kinematics, after_stress; under USL after_g2p too,
        which runs after the same pass). The same bits as the pass with MPM_FMA=0
        (round-off with contraction, the default); the stress read and written
        in the pass that has L_p, instead of L_p and the stress read again by a pass of their own
        (memory traffic: the 2D FLIP block's pass took 8 of 75 ns a particle). Not where MUSL's
        KINEMATICS pass is the vectorised `g2p_kinematics` (`splits_kinematics`), which has no
        update: that pass and the material's own were 10 % faster a step on the 2D FLIP block than
        the scalar pass with the update (`git show 63f7e3a^:docs/benchmarks.md`, "Speed, twentieth part")."""
        hooks = self.sim.hooks
        musl = self.sim.scene.method.scheme == "musl"
        return (self._has_update_lines and not hooks.after_kinematics and not hooks.after_stress
                and (musl or not hooks.after_g2p) and not (musl and splits_kinematics))

    # -- the transfers ----------------------------------------------------------------------

    def _p2g(self, acc: np.ndarray) -> None:
        sim = self.sim
        p, g, c, bad = sim.particles, sim.grid, sim.copies, self._bad
        # (L_p put off is C_p: `_g2p`)
        L = self._affine_matrix if p.pending("L") else p.stored("L")
        # formed while it is a function of the state (Particles.derived), even when a frame or a
        # checkpoint has read it since: the bits do not depend on what was read; an initial
        # stress or one assigned is the state, and is read, unless forming it gives it (`_rests`)
        fold, inline = self.plan.fold, p.derived("stress") or self._rests(L)
        kernel = self.plan.p2g
        if kernel.startswith("p2g_mls") and _contiguous(p.x, p.v, self._affine_matrix, p.F, L, acc):
            variant = self._p2g_mls_variants[inline, acc.shape[0] == 1]   # (one row: a shared acceleration)
            targets = (self._lanes()[0],) if kernel == "p2g_mls_lanes" else (c.mass, c.momentum)
            getattr(self._kernels, kernel)(
                variant, *_flat(p.x, p.v, self._affine_matrix), p.mass, p.volume, p.stored("stress"), *_flat(p.F, L),
                p.volume0, self._stress_parameters, *_flat(acc), *self._frame, self._d_inv, g.mass, g.momentum,
                *targets, bad, self.dt)
        elif kernel == "p2g_lanes":
            self._kernels.p2g_lanes(self._p2g_variants[fold, inline], p.x, p.v, self._affine_matrix, p.mass, p.volume,
                                    p.stored("stress"), p.F, L, p.volume0, self._stress_parameters, acc, self._frame,
                                    self._d_inv, g.mass, g.momentum, self._lanes()[0], bad, self.dt)
        else:
            self._kernels.p2g(self._p2g_variants[fold, inline], p.x, p.v, self._affine_matrix, p.mass, p.volume,
                              p.stored("stress"), p.F, L, p.volume0, self._stress_parameters, acc, self._frame,
                              self._d_inv, g.mass, g.momentum, g.force, c.mass, c.momentum, c.force, bad, self.dt,
                              *self._heat_p2g(), *self._contact_p2g())
        outside = first_of(bad)
        if outside >= 0:
            sim.fail(outside, "position", f"left the grid at {np.array2string(p.x[outside], precision=6)}")

    def _rests(self, L: np.ndarray) -> bool:
        """Whether P2G may form a stress that is still the state's (set before the first step,
        not yet `derived`) because forming it gives the same: a zero stress stored, and the
        material's stress lines giving exactly zero at every particle's state (the model's
        `stress_free`: a body at rest in its reference configuration). The first step then runs
        the P2G of every later step, instead of a variant compiled for that one step (3-4 s
        cold on one thread, more for the parallel form). Asked only while the stress is not
        derived: at the first step (the update puts the stress off from then on) and after an
        assignment."""
        p = self.sim.particles
        return (self.plan.forms_stress and self._stress_model.stress_free(p.F, L, p.volume, p.volume0)
                and rows_equal(p.stored("stress"), 0.0))

    def _lanes(self) -> tuple[np.ndarray, np.ndarray]:
        """The (threads, n_nodes, 4) rows `p2g_lanes` adds into and the (n_nodes, 4) velocities
        `g2p_lanes` reads, (re)allocated when the grid is placed anew (their contents are
        written by the kernels before they are read)."""
        n, threads = self.sim.grid.n_nodes, self.sim.threads
        if self._node_lanes.shape != (threads, n, 4):
            self._node_lanes = np.empty((threads, n, 4))
            self._velocity_lanes = np.empty((n, 4))
        return self._node_lanes, self._velocity_lanes

    def _integrate(self, dt: float) -> None:
        """After a folded P2G, v~_I^{t+dt} = (mv)_I / m_I = v_I^t, dt f_I being in (mv)_I already: the
        same bits as integrate_nodes with f_I = 0 ((mv)_I, summed from +0, is never -0), without
        its second division (2D block, 226^2 nodes: 307 -> 179 us at one thread, 305 -> 131 at two)."""
        if self.plan.fold:
            g = self.sim.grid
            kernels.nodal_velocity(self.sim.spec[0], g.mass, g.momentum, g.v_old)
            np.copyto(g.v_new, g.v_old)
        else:
            super()._integrate(dt)

    def grid_to_particles(self, dt: float, remap: bool, kinematics: bool = False) -> None:
        if remap:
            self.sim.grid.momentum.fill(0.0)
            self._g2p(dt, fused.REMAP)                 # v_p, C_p; (mv)_I again; v_pic kept for the move
        else:
            assert kinematics, "the fused USL pass moves the particles and updates L, F, V together"
            self._g2p(dt, fused.USL)                   # v_p, C_p, x_p; L_p, F_p, V_p
        self._after_g2p(dt)
        if kinematics:
            self._after_kinematics(dt, self.sim.grid.v_new)

    def kinematics(self, dt: float, v_grid: np.ndarray) -> None:
        assert v_grid is self.sim.grid.v_new, "the fused kinematics pass reads v_I^{t+dt}"
        self._g2p(dt, fused.KINEMATICS)                # L_p, F_p, V_p; x_p += dt v_pic
        self._after_kinematics(dt, v_grid)

    def _g2p(self, dt: float, mode: int) -> None:
        sim, plan = self.sim, self.plan
        p, g, bad = sim.particles, sim.grid, self._bad
        # MLS's USL gather: L_p = B_p D_p^-1 is C_p to the bit, copied only when something reads it
        # (where the stress is formed in P2G, no material reads it at each step)
        l_is_c = mode == fused.USL and plan.l_is_c
        updates = mode != fused.REMAP and plan.updates_stress
        kernel = {fused.USL: plan.g2p_usl, fused.KINEMATICS: plan.g2p_kinematics}.get(mode, "g2p")
        if kernel == "g2p_mls" and _contiguous(p.x, p.v, self._affine_matrix, p.F, g.v_new):
            self._kernels.g2p_mls(*_flat(p.x, p.v, self._affine_matrix, p.F, g.v_new), p.volume, p.volume0,
                                  *self._frame, self._d_inv, dt, sim.copies.momentum.shape[0] + 1, bad)
        elif kernel == "g2p_lanes":
            self._kernels.g2p_lanes(p.x, p.v, self._affine_matrix, p.F, p.volume, p.volume0, self._frame, g.v_new,
                                    self._lanes()[1], dt, self._d_inv, sim.threads, bad)
        elif kernel == "g2p_kinematics" and _contiguous(p.x, sim.rate, p.stored("L"), p.F, g.v_new):
            self._kernels.g2p_kinematics(self._support, *_flat(p.x, sim.rate, p.stored("L"), p.F, g.v_new), p.volume,
                                         p.volume0, *self._frame, dt, sim.copies.momentum.shape[0] + 1, bad)
        else:
            self._g2p_kernel(dt, mode, l_is_c, updates)
        if l_is_c:
            p.defer("L", lambda: np.copyto(p.stored("L"), self._affine_matrix))
        sim.check_inversion(first_of(bad))

    def _g2p_kernel(self, dt: float, mode: int, l_is_c: bool, updates: bool) -> None:
        sim = self.sim
        p, g, bad = sim.particles, sim.grid, self._bad
        self._kernels.g2p(self._g2p_variants[mode, l_is_c, updates], p.x, p.v, self._affine_matrix, p.mass,
                          p.stored("L"), p.F, p.volume, p.volume0, sim.rate, self._frame, g.v_old, g.v_new, g.momentum,
                          sim.flip_ratio, dt, self._d_inv, sim.copies.momentum, p.stored("stress"),
                          self._stress_parameters, bad, *self._heat_g2p(mode), *self._contact_g2p())

    # -- conduction (nothing without it) ----------------------------------------------------

    def _heat_p2g(self) -> tuple:
        """The thermal kernels' extra P2G arguments (read at each call: the hook's nodal
        arrays follow the grid's placements, the particles' their migration)."""
        conduction = self.sim.conduction
        if conduction is None:
            return ()
        x = self.sim.particles.extra   # (the kernel zeroes heat, each thread its array)
        return x["heat_capacity"], x["temperature"], x["heat_flux"], conduction.heat, conduction.copies_heat

    def _heat_g2p(self, mode: int) -> tuple:
        conduction = self.sim.conduction
        if conduction is None:
            return ()
        x = self.sim.particles.extra   # (the REMAP kernel zeroes remapped)
        return (x["heat_capacity"], x["temperature"], x["conductivity"], x["heat_flux"], conduction.T_change,
                conduction.T_new, conduction.held_mark, conduction.remapped, conduction.copies_remapped)

    # -- contact with a field per body (nothing without it) -----------------------------------

    def _contact_p2g(self) -> tuple:
        """The contact kernels' extra P2G arguments: the fields and the normals' arrays (zeroed)."""
        contact = self.sim.field_contact
        if contact is None:
            return ()
        contact.presence.fill(0.0)
        contact.gradient.fill(0.0)
        return (self.sim.particles.body, contact.field_of_body, self.sim.grid.n_nodes, contact.presence,
                contact.gradient, contact.copies_presence, contact.copies_gradient)

    def _contact_g2p(self) -> tuple:
        contact = self.sim.field_contact
        if contact is None:
            return ()
        return self.sim.particles.body, contact.field_of_body, self.sim.grid.n_nodes


def _stress_model(sim):
    """The scene's one material where P2G can form its stress (`stress_lines`) or G2P can update
    it (`stress_update_lines`)."""
    models = {id(model): model for model, _ in sim.materials}
    if len(sim.scene.materials) != 1 or len(models) != 1:
        return None
    model = next(iter(models.values()))
    return model if has_lines(model, "stress_lines") or has_lines(model, "stress_update_lines") else None


def has_lines(model, kind: str) -> bool:
    """Whether the model's `kind` lines ("stress_lines", "stress_update_lines") are its stress
    update: the class that gives them is the one that gives `update_stress`. A model that
    derives from one with lines and updates the stress its own way (J2, Drucker-Prager and
    Mohr-Coulomb over linear elasticity) inherits lines that are not its update."""
    def owner(name):
        return next((c for c in type(model).__mro__ if name in vars(c)), None)
    return model is not None and owner(kind) is not None and owner(kind) is owner("update_stress")


def _material_lines(sim, model, kind: str) -> tuple | None:
    """(the material's model name, its `kind` lines, its number of parameters) for the generated
    kernels, where the model has such lines (the scene's one material names the module)."""
    if not has_lines(model, kind):
        return None
    return (next(iter(sim.scene.materials.values())).model, getattr(model, kind)(sim.scene.dimension),
            len(model.stress_parameters()))


def _flat(*arrays: np.ndarray) -> tuple:
    """Views of C-contiguous arrays as one row (no copy: the kernel writes through them)."""
    return tuple(a.reshape(-1) for a in arrays)


def _contiguous(*arrays: np.ndarray) -> bool:
    """Whether a kernel may take flat views of the arrays (`_flat`)."""
    return all(a.flags.c_contiguous for a in arrays)
