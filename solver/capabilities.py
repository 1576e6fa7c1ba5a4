"""What the solver implements today.

The scene schema (solver/scene.py) describes the whole contract of SCENE.md; a
feature listed there but not here is rejected at validation with a
"not supported yet" error naming the field. An issue that implements a feature
adds it here in the same change.
"""

FORMULATIONS = frozenset({"ulmpm", "tlmpm"})
SCHEMES = frozenset({"musl", "usl", "usf"})
SHAPE_FUNCTIONS = frozenset({"linear", "gimp", "cpgimp", "quadratic_bspline", "cubic_bspline", "bernstein"})
TRANSFERS = frozenset({"flip", "pic", "apic"})
MATERIAL_MODELS = frozenset({"linear_elastic", "neo_hookean", "fluid", "ideal_gas", "rigid", "j2_plasticity", "johnson_cook"})
GEOMETRIES = frozenset({"box", "sphere", "cylinder", "union", "difference", "intersection"})
BOUNDARY_CONDITIONS = frozenset({"velocity", "wall"})
WALL_MODES = frozenset({"stick", "slip"})
AXISYMMETRIC = True
MAX_PROCESSES = 64   # MPI ranks (solver/parallel); the service caps jobs further (MPM_MAX_PROCESSES)

# Output fields the solver can write per particle (id, body and mass are always written).
OUTPUT_FIELDS = frozenset({
    "position", "velocity", "stress", "mass", "volume", "density", "pressure",
    "velocity_magnitude", "von_mises", "deformation_gradient", "strain_energy_density",
    "pressure_smoothed", "internal_energy",
    "plastic_strain", "damage", "temperature",
})
