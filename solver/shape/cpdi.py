"""CPDI (review 3.6; kernel: solver/shape/kernels/cpdi.py): convected particle domains."""

from dataclasses import replace

from solver.shape.registry import ShapeFunction

R4 = ShapeFunction(
        # CPDI-R4 (1D: CPDI-L2): the particle's domain, a box of side h / particles_per_cell,
        # follows F as a parallelogram (parallelepiped); the weights are the hat functions
        # at its corners. Four nodes per axis: the corners may reach one cell either side
        # of the particle's own (a domain up to 2h wide per axis).
        name="cpdi_r4", support=4, kernels="solver.shape.kernels.cpdi", least_cells=3,
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
                               "tetrahedra, CPDI-Tet4, not implemented): use 'cpdi_r4' in 1D and 3D")

SHAPE_FUNCTIONS = (R4, Q4)
