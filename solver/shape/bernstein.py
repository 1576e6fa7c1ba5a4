"""Quadratic Bernstein functions (review 3.5; kernel: solver/shape/kernels/bernstein.py): TLMPM only."""

from solver.shape.registry import ShapeFunction

SHAPE_FUNCTIONS = (
    ShapeFunction(
        name="bernstein", support=3, kernels="solver.shape.kernels.bernstein",
        even_cells=True,   # an element spans two grid cells
        # Bernstein functions are only C0 across cells: [R] 3.5 recommends them for TLMPM only.
        formulations=frozenset({"tlmpm"}),
        formulation_refusal="'bernstein' is only supported with formulation 'tlmpm': its gradient jumps across "
                            "element ends and it does not interpolate, so particles that move across elements "
                            "(as they do in ulmpm) get the cell-crossing force noise; tlmpm evaluates it once, "
                            "in the reference configuration",
    ),
)
