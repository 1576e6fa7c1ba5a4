"""Linear hat functions (review eq. 3.1-3.3; kernel: solver/shape/kernels/linear.py)."""

from solver.shape.registry import ShapeFunction

SHAPE_FUNCTIONS = (
    ShapeFunction(
        name="linear", support=2, kernels="solver.shape.kernels.linear",
        # see solver/transfer.py: C_p = sum v~_I grad w^T is unbounded on nearly empty nodes
        apic=False,
        apic_refusal="'apic' does not work with 'linear' hat functions: the affine matrix takes the unbounded "
                     "accelerations of nearly empty nodes, whose hat gradients do not vanish, and the run blows up; "
                     "use gimp, quadratic_bspline or cubic_bspline",
    ),
)
