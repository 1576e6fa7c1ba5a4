"""The heat verification cases (tests/verification/test_heat.py, benchmarks/heat.py):
scenes, exact solutions and the measured errors.

- E12 ([R] 5.3.3, eq. 5.27): a unit bar, rho = c = k = 1, T = 0 at t = 0, the right
  end held at 1 and the left at 0 (the exact series implies it), 1 particle per cell.
- E13 ([R] eq. 5.28): the unit square at 0, its boundary held at 100, 4 particles per
  cell; the boundary temperature is held on the grid nodes (Algorithm 8), where the
  source held the particles of the boundary cells.
- A heat flux through a face: sum_p m c T_p gains exactly the heat that came in.
- Axisymmetric conduction in a thick tube (inner wall 0, outer wall 1): the steady
  state is ln(r / r1) / ln(r2 / r1), which the radial term makes differ from the
  straight line a plane run gives.
- Thermal expansion: a free bar heated uniformly takes the strain alpha dT, a
  clamped one the stress -E alpha dT (poisson_ratio 0: uniaxial strain is uniaxial
  stress), in each solid model.
"""
from __future__ import annotations

import math

import numpy as np

from solver.scene_checks import load_scene
from solver.stepper import ExplicitMPM

UNIT = {"density": 1.0, "youngs_modulus": 1.0, "poisson_ratio": 0.0, "thermal_conductivity": 1.0,
        "specific_heat": 1.0}


def bar_scene(cells: int, dt: float, end: float = 0.05, dim: int = 1) -> dict:
    """E12 as a scene (the stick walls only keep the mechanics, which has no load, idle); in
    2D or 3D a bar of two cells' cross-section, insulated on its sides."""
    h = 1.0 / cells
    upper = [1.0] + [2 * h] * (dim - 1)
    return {"dimension": dim, "method": {"scheme": "musl"},
            "grid": {"lower": [0.0] * dim, "upper": upper, "cell_size": h},
            "materials": {"bar": {"model": "linear_elastic", **UNIT}},
            "bodies": [{"name": "bar", "material": "bar",
                        "geometry": {"type": "box", "lower": [0.0] * dim, "upper": upper},
                        "particles_per_cell": 1, "initial_temperature": 0.0}],
            "boundary_conditions": [{"type": "temperature", "face": "x-", "temperature": 0.0},
                                    {"type": "temperature", "face": "x+", "temperature": 1.0},
                                    {"type": "wall", "face": "x-", "mode": "stick"},
                                    {"type": "wall", "face": "x+", "mode": "stick"}],
            "time": {"end": end, "dt": dt}, "output": {"fields": ["temperature", "heat_flux"]}}


def bar_exact(x: np.ndarray, t: float, terms: int = 400) -> np.ndarray:
    """[R] eq. 5.27 with T0 = 0, T1 = 1 (400 terms: the tail is below exp(-400^2 pi^2 t) at t >= 0.0075)."""
    n = np.arange(1, terms + 1)[:, None]
    return x + 2 * np.sum((-1.0)**n / (n * np.pi) * np.exp(-(n * np.pi)**2 * t) * np.sin(n * np.pi * x), axis=0)


def advance_to(sim: ExplicitMPM, t: float, dt: float) -> None:
    while sim.time < t - 1e-12:
        sim.advance(min(dt, t - sim.time))


def bar_errors(cells: int, dt: float, times=(0.0075, 0.03, 0.05), dim: int = 1, formulation: str = "ulmpm",
               stretch: float = 1.0) -> dict[float, tuple[float, float]]:
    """{t: (max nodal error of T_I^{t+dt}, max particle error)} of E12.

    TLMPM with `stretch` lambda: the bar held stretched to lambda times its length (F = lambda I
    set once; at rest and hypoelastic, nothing changes it), same mass and k. In X its heat
    equation is rho c dT/dt = (k / lambda) d2T/dX2 (the nominal flux J C^-1 k grad0 T), so
    T(X, t) = E12's T(X, t / lambda): the reference-configuration terms are checked."""
    scene = bar_scene(cells, dt, max(times), dim)
    scene["method"]["formulation"] = formulation
    sim = ExplicitMPM(load_scene(scene))
    if stretch != 1.0:
        sim.particles.F[:] *= stretch
    nodes = sim.grid.node_positions()[:, 0]
    out = {}
    for t in times:
        advance_to(sim, t, dt)
        particles = sim.particles
        where = particles.X[:, 0] if formulation == "tlmpm" else particles.x[:, 0]
        exact = bar_exact(nodes, sim.time / stretch), bar_exact(where, sim.time / stretch)
        grid_error = np.max(np.abs(sim.conduction.grid_temperature() - exact[0]))
        particle_error = np.max(np.abs(particles.extra["temperature"] - exact[1]))
        out[t] = (float(grid_error), float(particle_error))
    return out


def held_neighbour_errors(cells: int, dt: float, t: float) -> list[tuple[float, float]]:
    """E12 at t: for the particle of each end cell (whose stencil reaches a held node), (its
    distance from the exact series, the bound it is held to): the largest nodal error of its
    cell's two nodes, which it interpolates (thermal_kernels.takes_grid_temperature), plus
    linear interpolation's h^2 / 8 max |T_xx| over the cell (T_xx = T_t, by differences of the
    series)."""
    sim = ExplicitMPM(load_scene(bar_scene(cells, dt, t)))
    advance_to(sim, t, dt)
    h = 1.0 / cells
    nodes = sim.grid.node_positions()[:, 0]
    nodal = np.abs(sim.conduction.grid_temperature() - bar_exact(nodes, sim.time))
    x, T = sim.particles.x[:, 0], sim.particles.extra["temperature"]
    out = []
    for p in (np.argmin(x), np.argmax(x)):
        cell = int(x[p] // h)
        span = np.linspace(cell * h, (cell + 1) * h, 21)
        curvature = np.max(np.abs(bar_exact(span, sim.time + 1e-6) - bar_exact(span, sim.time - 1e-6))) / 2e-6
        bound = max(nodal[cell], nodal[cell + 1]) + h * h / 8 * curvature
        out.append((float(abs(T[p] - bar_exact(x[p:p + 1], sim.time)[0])), float(bound)))
    return out


def plate_scene(cells: int, dt: float, end: float = 0.05) -> dict:
    faces = ("x-", "x+", "y-", "y+")
    return {"dimension": 2, "method": {"scheme": "musl"},
            "grid": {"lower": [0.0, 0.0], "upper": [1.0, 1.0], "cell_size": 1.0 / cells},
            "materials": {"plate": {"model": "linear_elastic", **UNIT}},
            "bodies": [{"name": "plate", "material": "plate",
                        "geometry": {"type": "box", "lower": [0.0, 0.0], "upper": [1.0, 1.0]},
                        "particles_per_cell": 2, "initial_temperature": 0.0}],
            "boundary_conditions": [{"type": "temperature", "face": f, "temperature": 100.0} for f in faces]
                                   + [{"type": "wall", "face": f, "mode": "stick"} for f in faces],
            "time": {"end": end, "dt": dt}}


def plate_exact(x: np.ndarray, y: np.ndarray, t: float, terms: int = 101) -> np.ndarray:
    """[R] eq. 5.28 with L = H = 1, T0 = 0, T1 = 100 (odd i, j below `terms`)."""
    total = np.zeros_like(x)
    for i in range(1, terms, 2):
        for j in range(1, terms, 2):
            total += (np.exp(-np.pi**2 * (i * i + j * j) * t) / (i * j)
                      * np.sin(i * np.pi * x) * np.sin(j * np.pi * y))
    return 100.0 - 1600.0 / np.pi**2 * total


def plate_error(cells: int, dt: float, t: float = 0.05) -> float:
    """Max nodal error of E13 at t, in kelvin (of T1 = 100)."""
    sim = ExplicitMPM(load_scene(plate_scene(cells, dt, t)))
    advance_to(sim, t, dt)
    xy = sim.grid.node_positions()
    return float(np.max(np.abs(sim.conduction.grid_temperature() - plate_exact(xy[:, 0], xy[:, 1], sim.time))))


def flux_scene(dim: int, flux, coefficient: float, steps: int = 200) -> dict:
    """A block filling the unit grid, insulated but for a flux through x+ and convection through x-."""
    lower, upper = [0.0] * dim, [1.0] * dim
    return {"dimension": dim, "method": {"scheme": "usl"},
            "grid": {"lower": lower, "upper": upper, "cell_size": 0.1},
            "materials": {"block": {"model": "linear_elastic", **UNIT}},
            "bodies": [{"name": "block", "material": "block", "geometry": {"type": "box", "lower": lower,
                                                                           "upper": upper},
                        "initial_temperature": 1.0}],
            "boundary_conditions": [{"type": "heat_flux", "face": "x+", "flux": flux},
                                    {"type": "convection", "face": "x-", "coefficient": coefficient, "ambient": 3.0},
                                    {"type": "wall", "face": "x-", "mode": "stick"}],
            "time": {"end": steps * 1e-3, "dt": 1e-3}}


def flux_balance(dim: int, flux=5.0, coefficient: float = 2.0, steps: int = 200) -> tuple[float, float]:
    """(gain of sum_p m c T_p, heat that came in through the faces) over the run."""
    sim = ExplicitMPM(load_scene(flux_scene(dim, flux, coefficient, steps)))
    start = sim.thermal_series()["thermal_energy"]
    for _ in range(steps):
        sim.advance(1e-3)
    series = sim.thermal_series()
    return series["thermal_energy"] - start, series["boundary_heat"]


R_IN, R_OUT = 1.0, 2.0


def tube_scene(axisymmetric: bool, cell: float = 0.05, end: float = 1.0, formulation: str = "ulmpm") -> dict:
    """A thick tube's wall r in [1, 2] (a slice of height 0.2), the inner wall held at 0, the outer at 1."""
    method = {"scheme": "musl"} if formulation == "ulmpm" else {"scheme": "musl", "formulation": formulation}
    return {"dimension": 2, "axisymmetric": axisymmetric, "method": method,
            "grid": {"lower": [R_IN, 0.0], "upper": [R_OUT, 0.2], "cell_size": cell},
            "materials": {"wall": {"model": "linear_elastic", **UNIT}},
            "bodies": [{"name": "wall", "material": "wall",
                        "geometry": {"type": "box", "lower": [R_IN, 0.0], "upper": [R_OUT, 0.2]},
                        "initial_temperature": 0.0}],
            "boundary_conditions": [{"type": "temperature", "face": "x-", "temperature": 0.0},
                                    {"type": "temperature", "face": "x+", "temperature": 1.0}]
                                   + [{"type": "wall", "face": f, "mode": "stick"} for f in ("x-", "x+", "y-", "y+")],
            "time": {"end": end}}


def tube_steady(r: np.ndarray) -> np.ndarray:
    return np.log(r / R_IN) / math.log(R_OUT / R_IN)


def tube_error(axisymmetric: bool, cell: float = 0.05, end: float = 1.0, formulation: str = "ulmpm") -> float:
    """Max nodal distance from the axisymmetric steady state ln(r/r1)/ln(r2/r1) at t = end
    (the slowest transient has decayed by exp(-pi^2 end))."""
    scene = load_scene(tube_scene(axisymmetric, cell, end, formulation))
    sim = ExplicitMPM(scene)
    dt = sim.stable_time_step(scene.time.cfl)
    advance_to(sim, end, dt)
    r = sim.grid.node_positions()[:, 0]
    return float(np.max(np.abs(sim.conduction.grid_temperature() - tube_steady(r))))


# --------------------------------------------------------------------------- thermal expansion

E, ALPHA, HEATING = 2.0e11, 1.0e-5, 100.0
SOLIDS = {
    "linear_elastic": {},
    "neo_hookean": {},
    "j2_plasticity": {"yield_stress": 1.0e9, "hardening_modulus": 0.0},   # stays elastic (E alpha dT = 2e8)
    "johnson_cook": {"A": 1.0e9, "B": 0.0, "n": 1.0, "C": 0.0, "reference_strain_rate": 1.0, "m": 1.0,
                     "room_temperature": 300.0, "melt_temperature": 1800.0, "specific_heat": 500.0,
                     "taylor_quinney": 0.9},
}
RAMP = 2.0e-3   # s: the heating time, 14 wave transits of the bar (c = 5000 m/s, L = 1 m)


def heated_bar_scene(model: str, clamped: bool, dim: int = 1, poisson_ratio: float = 0.0) -> dict:
    """A unit bar (block) at 300 K whose every node is held at 300 + 100 min(t / RAMP, 1): a
    uniform temperature rise. Clamped: the bar fills the grid, stick walls at x- and x+."""
    material = {"model": model, "density": 8000.0, "youngs_modulus": E, "poisson_ratio": poisson_ratio,
                "thermal_conductivity": 50.0, "specific_heat": 500.0, "thermal_expansion": ALPHA, **SOLIDS[model]}
    lower, upper = [0.0] * dim, [1.0] * dim
    conditions = [{"type": "temperature", "where": {"type": "box", "lower": [-9.0] * dim, "upper": [9.0] * dim},
                   "temperature": f"300 + {HEATING} * min(t / {RAMP}, 1)"}]
    if clamped:
        conditions += [{"type": "wall", "face": "x-", "mode": "stick"}, {"type": "wall", "face": "x+", "mode": "stick"}]
    return {"dimension": dim, "method": {"scheme": "musl"},
            "grid": {"lower": lower if clamped else [-0.5] * dim, "upper": upper if clamped else [1.5] * dim,
                     "cell_size": 0.05 if dim == 1 else 0.1},
            "materials": {"m": material},
            "bodies": [{"name": "bar", "material": "m", "geometry": {"type": "box", "lower": lower, "upper": upper},
                        "initial_temperature": 300.0}],
            "boundary_conditions": conditions, "time": {"end": 1.5 * RAMP}}


def heated_bar(model: str, clamped: bool, dim: int = 1, poisson_ratio: float = 0.0) -> ExplicitMPM:
    scene = load_scene(heated_bar_scene(model, clamped, dim, poisson_ratio))
    sim = ExplicitMPM(scene)
    advance_to(sim, scene.time.end, sim.stable_time_step(scene.time.cfl))
    return sim


def averaged_after_heating(model: str, dim: int, poisson_ratio: float, until: float = 3 * RAMP) -> dict[str, float]:
    """Time averages, from the end of the heating to `until`, of the mean normal strains
    F_aa - 1 and stresses of a free block (what vibration the ramp leaves averages out)."""
    scene = load_scene(heated_bar_scene(model, False, dim, poisson_ratio))
    sim = ExplicitMPM(scene)
    dt = sim.stable_time_step(scene.time.cfl)
    advance_to(sim, RAMP, dt)
    total, count = np.zeros(dim + 3), 0
    while sim.time < until - 1e-12:
        sim.advance(dt)
        p = sim.particles
        strains = [p.F[:, a, a].mean() - 1.0 for a in range(dim)]
        total += np.array(strains + [p.stress[:, a, a].mean() for a in range(3)])
        count += 1
    mean = total / count
    return {**{f"strain_{a}": mean[a] for a in range(dim)}, **{f"stress_{a}": mean[dim + a] for a in range(3)}}
