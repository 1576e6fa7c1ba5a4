"""uGIMP and cpGIMP (review 3.3; kernel: solver/shape/kernels/gimp.py)."""

from dataclasses import replace

from solver.shape.registry import ShapeFunction

GIMP = ShapeFunction(name="gimp", support=3, kernels="solver.shape.kernels.gimp", least_cells=2,
                     per_particle_data=True)
# cpGIMP is GIMP with boxes that follow the stretch: the same kernel, another evaluate.
CPGIMP = replace(GIMP, name="cpgimp", evaluate="evaluate_contiguous")

SHAPE_FUNCTIONS = (GIMP, CPGIMP)
