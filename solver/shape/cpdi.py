"""CPDI (review 3.6; kernel: solver/shape/kernels/cpdi.py): convected particle domains."""

from dataclasses import replace

from solver.shape.registry import ShapeFunction

R4 = ShapeFunction(
        # CPDI-R4 (1D: CPDI-L2): the particle's domain, a box of side h / particles_per_cell,
        # follows F as a parallelogram (parallelepiped); the weights are the hat functions
        # at its corners. `support` 4: the corners within one cell either side of the
        # particle's own, the widest stencil with several processes (the slabs' halo); on
        # one process the stencil widens past it to what the largest domain needs
        # (solver/shape/kernels/cpdi.py: support_needed).
        name="cpdi_r4", support=4, kernels="solver.shape.kernels.cpdi", least_cells=3, per_particle_data=True,
        # a domain within two cells per axis (most: h / particles_per_cell stretched less
        # than 2x) touches 3 nodes per axis: the compact stencil, 27 nodes in 3D against 64
        compact_support=3,
        # The domain follows the current F: weights evaluated once in the reference
        # configuration (tlmpm) would see the undeformed box, i.e. uGIMP without its
        # exact integral; use gimp there.
        formulations=frozenset({"ulmpm"}),
        formulation_refusal="'cpdi_r4' is only supported with formulation 'ulmpm': its particle domains follow "
                            "the current deformation, which tlmpm never evaluates weights in (use 'gimp' or "
                            "'cubic_bspline' with tlmpm)",
        axisymmetric=False,
        axisymmetric_refusal="'cpdi_r4' is not supported in axisymmetric scenes: CPDI needs axisymmetric forms "
                             "of its weights (review Remark 42, Nairn & Guilkey 2015), which the review does "
                             "not give; use 'linear' or 'cubic_bspline'",
)
# CPDI-Q4 (CPDI2): the domain's four corners are tracked with the grid velocity (eq. 3.38),
# so neighbouring quadrilaterals keep sharing their corners (no gaps, review Fig. 25).
Q4 = replace(R4, name="cpdi_q4", evaluate="evaluate_tracked", hook="hook",
             formulation_refusal=R4.formulation_refusal.replace("cpdi_r4", "cpdi_q4"),
             axisymmetric_refusal=R4.axisymmetric_refusal.replace("cpdi_r4", "cpdi_q4"),
             dimensions=frozenset({2}),
             dimension_refusal="'cpdi_q4' is for 2D scenes (quadrilaterals; the review's 3D tracked domains are "
                               "tetrahedra, 'cpdi_tet4'): use 'cpdi_r4' in 1D and 'cpdi_tet4' or 'cpdi_r4' in 3D")
# CPDI-Tet4 (3D): the domain's eight corners are tracked as cpdi_q4's four, and the hexahedron
# they span is split into six tetrahedra (the Kuhn split, conforming between neighbours), each
# with the review's Tet4 weights (3.6.3); the particle sits at the domain's volume centroid.
TET4 = replace(Q4, name="cpdi_tet4", hook="hook_tetrahedra",
               formulation_refusal=R4.formulation_refusal.replace("cpdi_r4", "cpdi_tet4"),
               axisymmetric_refusal=R4.axisymmetric_refusal.replace("cpdi_r4", "cpdi_tet4"),
               dimensions=frozenset({3}),
               dimension_refusal="'cpdi_tet4' is for 3D scenes (tetrahedra): use 'cpdi_q4' or 'cpdi_r4' in 2D "
                                 "and 'cpdi_r4' in 1D")

SHAPE_FUNCTIONS = (R4, Q4, TET4)
