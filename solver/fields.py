"""Per-particle output fields, derived from the state only when a frame asks for them."""
from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from solver import materials, shape
from solver.capabilities import ROW_BLOCK, ROW_LOCAL_FIELDS as ROW_LOCAL
from solver.seeding import box_sides
from solver.state import make_stencil

VOIGT = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))   # xx yy zz yz xz xy


def voigt(stress: np.ndarray) -> np.ndarray:
    return np.stack([stress[:, a, b] for a, b in VOIGT], axis=1)


def pressure(stress: np.ndarray) -> np.ndarray:
    """p = -tr(sigma)/3, positive in compression."""
    return -np.trace(stress, axis1=1, axis2=2) / 3.0


def von_mises(stress: np.ndarray) -> np.ndarray:
    """sqrt(3/2 s:s) with s the deviatoric stress."""
    dev = stress + pressure(stress)[:, None, None] * np.eye(3)
    return np.sqrt(1.5 * np.einsum("pij,pij->p", dev, dev))


def total_stress(particles) -> np.ndarray:
    """sigma = sigma' - p I: in a saturated soil (solver/pore_fluid.py) the particles' `stress`
    is the effective one and the pore pressure is apart; elsewhere the stress itself."""
    pore = particles.extra.get("pore_pressure")
    if pore is None:
        return particles.stress
    return particles.stress - pore[:, None, None] * np.eye(3)


def _pore_pressure(sim) -> np.ndarray:
    """p, positive in compression; zero where no material has a pore fluid."""
    p = sim.particles
    pore = p.extra.get("pore_pressure")
    return pore if pore is not None else np.zeros(p.count)


def through_grid(sim, values: np.ndarray) -> np.ndarray:
    """Particle values mapped to the nodes like the momentum (mass-weighted) and
    interpolated back ([R] 6.1.4 shows Sod's pressure at the nodes: smoother).

    The weights are those of the particles' current positions."""
    p, g = sim.particles, sim.grid
    s = make_stencil(p.count, p.dimension, sim.wide_support)
    shape.evaluate(sim.shape, sim.wide_spec, p.x, p, g, s)
    mw = p.mass[:, None] * s.w
    node_mass = np.bincount(s.idx.ravel(), mw.ravel(), minlength=g.n_nodes)
    node_sum = np.bincount(s.idx.ravel(), (mw * values[:, None]).ravel(), minlength=g.n_nodes)
    node_value = np.divide(node_sum, node_mass, out=np.zeros_like(node_sum), where=node_mass > 0)
    return (s.w * node_value[s.idx]).sum(axis=1)


def _particle_domain(sim) -> np.ndarray:
    """(n, 2^d * d): the corners of each particle's domain: cpdi_q4's tracked ones, else its
    seeded box carried by F (CPDI-R4's parallelogram, GIMP's box deformed, for any shape
    function), corner c at
    x_p + F diag(l0/2) s_c with s_c in {-1, 1}^d, axis 0 fastest: in 2D (x-, y-),
    (x+, y-), (x-, y+), (x+, y+), each as x, y."""
    from solver.shape.kernels.cpdi import CORNERS, LENGTH, domain_corners   # numba: only runs that write it

    p = sim.particles
    if CORNERS in p.extra:   # the tracked corners: cpdi_q4's x1 x2 x4 x3 in the order above, cpdi_tet4's in it
        corners = p.extra[CORNERS]
        return (corners[:, [0, 1, 3, 2]] if corners.shape[1] == 4 else corners).reshape(p.count, -1)
    length = p.extra.get(LENGTH)
    if length is None:
        length = box_sides(sim.scene, p.body)
    return domain_corners(p.x, length, p.F).reshape(p.count, -1)


def _strain_energy_density(sim) -> np.ndarray:
    p = sim.particles
    out = np.zeros(p.count)
    for material, sl in sim.materials:
        out[sl] = material.particle_strain_energy(p, sl) / p.volume[sl]
    return out


def _state(name: str, absent: float):
    """A per-particle state variable of the materials that track it; `absent` elsewhere
    (and everywhere when no material of the run tracks it)."""
    def field(sim) -> np.ndarray:
        values = sim.particles.extra.get(name)
        return values if values is not None else np.full(sim.particles.count, absent)
    return field


def _heat_flux(sim) -> np.ndarray:
    """q_p = -k grad T (solver/thermal.py); zero where nothing conducts."""
    p = sim.particles
    q = p.extra.get("heat_flux")
    return q if q is not None else np.zeros((p.count, p.dimension))


FIELDS = {
    "position": lambda sim: sim.particles.x,
    "velocity": lambda sim: sim.particles.v,
    "stress": lambda sim: voigt(total_stress(sim.particles)),
    "mass": lambda sim: sim.particles.mass,
    "volume": lambda sim: sim.particles.volume,
    "density": lambda sim: sim.particles.mass / sim.particles.volume,
    "pressure": lambda sim: pressure(total_stress(sim.particles)),
    "pressure_smoothed": lambda sim: through_grid(sim, pressure(total_stress(sim.particles))),
    "von_mises": lambda sim: von_mises(sim.particles.stress),   # (the pore pressure has no deviator)
    "velocity_magnitude": lambda sim: np.linalg.norm(sim.particles.v, axis=1),
    "deformation_gradient": lambda sim: sim.particles.F.reshape(sim.particles.count, -1),
    "strain_energy_density": _strain_energy_density,
    "heat_flux": _heat_flux,
    "particle_domain": _particle_domain,
    "pore_pressure": _pore_pressure,
    "effective_stress": lambda sim: voigt(sim.particles.stress),
    "reference_position": lambda sim: sim.particles.X,   # kept where a frame asks for it (stepper.py)
}
"""The fields of every scene (capabilities.SCENE_FIELDS names them for the scene's checks);
the materials add their state's (plastic_strain, damage, temperature, internal_energy, ...:
solver.materials.output_fields; capabilities.OUTPUT_FIELDS refuses a name in both)."""


def field(name: str):
    """The function sim -> per-particle values of output field `name`."""
    if name in FIELDS:
        return FIELDS[name]
    return _state(name, materials.output_fields()[name])


class FrameFields(Mapping):
    """A frame's fields by name, each formed from the state when it is read (and not kept):
    a writer that takes them one at a time holds one formed field at once, not the frame;
    one that takes them by `blocks` holds a block of one (the Taylor bar's 6-component stress:
    48 bytes a particle formed whole, 3 MiB in blocks)."""

    def __init__(self, sim, names):
        self._sim = sim
        self._names = tuple(dict.fromkeys(("id", "body", "mass", "position", *names)))

    def __getitem__(self, name: str) -> np.ndarray:
        if name not in self._names:
            raise KeyError(name)
        p = self._sim.particles
        always = {"id": p.id, "body": p.body, "mass": p.mass, "position": p.x}
        return always[name] if name in always else np.ascontiguousarray(field(name)(self._sim))

    def __iter__(self):
        return iter(self._names)

    def __len__(self) -> int:
        return len(self._names)

    def blocks(self, name: str):
        """(first row, values) of field `name`: a ROW_LOCAL field formed ROW_BLOCK rows at a time,
        any other as one block of every row."""
        count = self._sim.particles.count
        if name not in ROW_LOCAL or count <= ROW_BLOCK or name not in self._names:
            yield 0, self[name]
            return
        for start in range(0, count, ROW_BLOCK):
            rows = _Rows(self._sim.particles, start, min(start + ROW_BLOCK, count))
            yield start, np.ascontiguousarray(field(name)(rows))


class _Rows:
    """The simulation as a ROW_LOCAL field reads it: rows start..stop-1 of the particles' arrays
    (views), as `sim.particles`."""

    def __init__(self, particles, start: int, stop: int):
        self.particles = self
        self._source, self._rows = particles, slice(start, stop)
        self.count = stop - start
        self.dimension = particles.dimension
        self.extra = {name: values[self._rows] for name, values in particles.extra.items()}

    def __getattr__(self, name: str) -> np.ndarray:
        return getattr(self._source, name)[self._rows]


def frame_fields(sim, names) -> FrameFields:
    """id, body, mass and position always; then every requested field (formed when read)."""
    return FrameFields(sim, names)
