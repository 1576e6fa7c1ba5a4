"""Absorbing (viscous, Lysmer & Kuhlemeyer 1969) boundaries, a hook on the summed nodal
forces before the grid update.

A face of the grid marked {"type": "absorbing", "face": ...} carries dashpots: the
traction -rho c_p v_n on the normal velocity and -rho c_s v_t on the tangential ones,
so a plane wave meeting the face at normal incidence leaves the grid instead of being
reflected by the free surface the face would otherwise be. On the grid this is the
nodal force

    f_I = -A_I (rho c_p v_In n + rho c_s v_It),    v_I = (mv)_I / m_I

on the face's nodes that hold mass, with A_I the node's share of the face (h^(dim-1),
half of it on the face's own edges; per unit area in 1D, per unit thickness in 2D).
rho, c_p = sqrt((lambda + 2 mu) / rho) and c_s = sqrt(mu / rho) are the elastic ones of
the material of the bodies that reach the face (the scene checks there is one). Oblique
and surface waves are absorbed in part (Lysmer's dashpots are exact at normal
incidence). The dashpots' work, dt sum f_I . (v_I^t + v~_I^{t+dt}) / 2, goes into
`boundary_work` (negative: the energy carried out).
"""
from __future__ import annotations

import math

import numpy as np
from solver.jit import njit

from solver.boundary import AXES, face_material, face_nodes


@njit(cache=True)
def dashpots(nodes, axis, area, z_normal, z_shear, mass, momentum, force, mass_cutoff, out):
    """Add -A (rho c) v to `force` on `nodes` above the mass cut-off; also into `out`."""
    for k in range(nodes.shape[0]):
        i = nodes[k]
        m = mass[i]
        for a in range(force.shape[1]):
            f = 0.0
            if m > mass_cutoff:
                f = -area[k] * (z_normal if a == axis else z_shear) * momentum[i, a] / m
            out[k, a] = f
            force[i, a] += f


@njit(cache=True)
def work(dt, nodes, out, v_old, v_new):
    total = 0.0
    for k in range(nodes.shape[0]):
        i = nodes[k]
        for a in range(out.shape[1]):
            total += out[k, a] * (v_old[i, a] + v_new[i, a])
    return 0.5 * dt * total


def impedances(material) -> tuple[float, float]:
    """(rho c_p, rho c_s) of an elastic material."""
    lam, mu = material.lame_parameters()
    return math.sqrt(material.density * (lam + 2 * mu)), math.sqrt(material.density * mu)


def node_areas(grid, face: str, nodes: np.ndarray) -> np.ndarray:
    """Each face node's share of the face: the product of the tangential cell sizes,
    halved for every tangential axis along which the node is at an end."""
    axis = AXES[face[0]]
    area = np.ones(nodes.size)
    for a in range(len(grid.h)):
        if a == axis:
            continue
        position = (nodes // grid.strides[a]) % (grid.cells[a] + 1)
        at_end = (position == 0) | (position == grid.cells[a])
        area *= np.where(at_end, 0.5, 1.0) * grid.h[a]
    return area


class AbsorbingFaces:
    def __init__(self, scene, grid):
        self.faces = []
        for condition in scene.boundary_conditions:
            if condition.type != "absorbing":
                continue
            nodes = face_nodes(grid, condition.face)
            z_normal, z_shear = impedances(face_material(scene, condition.face))
            self.faces.append((nodes, AXES[condition.face[0]], node_areas(grid, condition.face, nodes),
                               z_normal, z_shear, np.zeros((nodes.size, scene.dimension))))

    def before_update(self, sim, dt: float) -> None:
        g = sim.grid
        for nodes, axis, area, z_normal, z_shear, out in self.faces:
            dashpots(nodes, axis, area, z_normal, z_shear, g.mass, g.momentum, g.force, sim.mass_cutoff, out)

    def after_g2p(self, sim, dt: float) -> None:
        """The grid velocities of this step are constrained by now (as for damping)."""
        for nodes, _, _, _, _, out in self.faces:
            sim.work.add("boundary_work", work(dt, nodes, out, sim.grid.v_old, sim.grid.v_new))
