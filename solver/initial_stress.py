"""Initial stress of bodies at t = 0 (the body's `initial_stress`).

"geostatic": the stress of a body at rest under gravity with horizontal ground,
column by column (a slope too):

    sigma_v = -rho g d,   sigma_h = k0 sigma_v   (every other axis, the out-of-plane
                                                  and the hoop one included)

with d the depth below the body's top in the particle's vertical column: the highest
particle of the column plus half a particle spacing (the surface of the material the
particles stand for). k0 defaults to Jaky's 1 - sin(friction_angle). In a saturated
soil (a material with a pore fluid) the stress is the effective one: sigma_v less the
pore pressure's rise below the column's top, k0 applied to that (solver/pore_fluid.py). Without it a
body starts stress-free and collapses onto itself under a gravity shock: waves of
amplitude rho g H in stress, g H / c in velocity, ring for many periods.
"""
from __future__ import annotations

import numpy as np

from solver.pore_fluid_schema import initial_pore_pressure


def vertical_axis(gravity) -> tuple[int, float]:
    """(axis, sign of up along it) of a gravity along one axis (the scene checked it)."""
    axis = int(np.flatnonzero(np.asarray(gravity))[0])
    return axis, -float(np.sign(gravity[axis]))


def apply(scene, particles) -> None:
    """Set the initial stress of every body that asks for one (before the materials' own
    start values, solver/state.py: Cam-Clay starts its p_c from it)."""
    for index, body in enumerate(scene.bodies):
        if body.initial_stress is None:
            continue
        selected = np.flatnonzero(particles.body == index)
        if selected.size:
            particles.stress[selected] = geostatic_stress(scene, body, particles.x[selected],
                                                          particles.mass[selected] / particles.volume[selected])


def geostatic_stress(scene, body, x: np.ndarray, density: np.ndarray) -> np.ndarray:
    """The 3x3 geostatic stress at the particles `x` of `body` (density per particle)."""
    axis, up = vertical_axis(scene.gravity)
    g = abs(float(scene.gravity[axis]))
    spacing = np.asarray(scene.cell_sizes()) / body.particles_per_cell
    depth = depth_below_top(x - np.asarray(scene.grid_lower()), axis, up, spacing)
    material = scene.materials[body.material]
    k0 = body.initial_stress.k0 if body.initial_stress.k0 is not None else material.default_k0()
    vertical = -density * g * depth
    if material.pore_fluid is not None:   # a saturated soil: its stress model holds the effective stress
        vertical = vertical + pore_pressure_rise(scene, body, x, depth, axis, up)
    stress = np.zeros((x.shape[0], 3, 3))
    for a in range(3):
        stress[:, a, a] = vertical if a == axis else k0 * vertical
    return stress


def pore_pressure_rise(scene, body, x: np.ndarray, depth: np.ndarray, axis: int, up: float) -> np.ndarray:
    """p(x) - p(top of the column): the share of the total geostatic stress the pore water
    carries (the buoyancy below the water table), so that sigma' = sigma - (-p I) starts from
    the weight less the water's. A column under water thus starts at sigma'_v = -(rho - rho_w) g d."""
    top = x.copy()
    top[:, axis] += up * depth
    return initial_pore_pressure(scene, body, x) - initial_pore_pressure(scene, body, top)


def depth_below_top(x: np.ndarray, axis: int, up: float, spacing: np.ndarray) -> np.ndarray:
    """Depth of each particle below the top of its vertical column: the particles whose
    horizontal coordinates (from the grid's lower corner, where the seeding lattice
    starts) lie in the same spacing-wide interval."""
    height = up * x[:, axis]
    horizontal = [a for a in range(x.shape[1]) if a != axis]
    if horizontal:
        keys = np.floor(x[:, horizontal] / spacing[horizontal]).astype(np.int64)
        _, column = np.unique(keys, axis=0, return_inverse=True)
        column = column.reshape(-1)
    else:
        column = np.zeros(x.shape[0], dtype=np.int64)
    top = np.full(column.max() + 1, -np.inf)
    np.maximum.at(top, column, height)
    return top[column] + 0.5 * spacing[axis] - height
