"""Cubic B-splines, boundary-modified (review 3.4; kernel: solver/shape/kernels/cubic_bspline.py).

D_p is h^2/3 inside the grid but not near its ends, where the functions are
modified: no uniform APIC constant."""

from solver.shape.registry import ShapeFunction

SHAPE_FUNCTIONS = (ShapeFunction(name="cubic_bspline", support=4, kernels="solver.shape.kernels.cubic_bspline",
                                 least_cells=3, smooth=True),)
