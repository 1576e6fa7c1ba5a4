"""Quadratic B-splines (review eq. 5.10; kernel: solver/shape/kernels/quadratic_bspline.py).

No boundary-modified variant: a particle within h/2 of a grid end would need a
node beyond it, so bodies keep half a cell from the grid ends (validation)."""

from solver.shape.registry import ShapeFunction

SHAPE_FUNCTIONS = (ShapeFunction(name="quadratic_bspline", support=3, kernels="solver.shape.kernels.quadratic_bspline",
                                 apic_d=0.25, least_cells=2, end_margin=0.5, smooth=True),)
