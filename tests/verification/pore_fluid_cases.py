"""The saturated soil (two-phase, solver/pore_fluid.py) verification cases
(tests/verification/test_pore_fluid.py, benchmarks/two_phase.py): scenes, exact solutions
and the measured errors.

- Terzaghi's 1D consolidation: a column of height H on an impervious, fixed base, laterally
  confined (slip walls), drained at its top, under a load q. It starts from the undrained
  state, p = q and sigma' = 0 (`initial_pore_pressure` uniform: the total stress -q balances
  the load), so nothing rings. With a compressible fluid and an elastic skeleton (nu = 0:
  the constrained modulus E_oed = E) the 1D mass balance and equilibrium give the diffusion
  equation dp/dt = c_v d2p/dz2 with c_v = (k / (rho_w g_n)) / (1/E_oed + n/K_w) (Terzaghi's
  with the fluid's storage added to the skeleton's), p = 0 at the top, dp/dz = 0 at the base:

      p(z, t) / q = sum_m 2/M sin(M z/H) exp(-M^2 Tv),   M = pi (2m + 1) / 2,  Tv = c_v t / H^2
      U(Tv) = 1 - sum_m 2/M^2 exp(-M^2 Tv)               (z from the drained top)

- Undrained loading: the same column sealed (no drained face), loaded suddenly, with local
  damping to let the waves die: p = q (K_w/n) / (K_w/n + E_oed), which is q within 0.05 % for
  water in a soft skeleton (B ~ 1).
"""
from __future__ import annotations

import math

import numpy as np

from solver.pore_fluid_schema import G_N
from solver.scene_checks import load_scene
from solver.stepper import ExplicitMPM

HEIGHT = 1.0
LOAD = 1.0e4           # q, Pa
SKELETON = {"density": 2000.0, "youngs_modulus": 1.0e6, "poisson_ratio": 0.0,
            "friction_angle": 30.0, "cohesion": 1.0e5}   # strong enough to stay elastic
# a fluid as compressible as 9 times the skeleton's stiffness (K_w / n = 9 E_oed): B = 0.9 in an
# undrained step, and a pressure diffusion only 10 times c_v, so the explicit step is not tied
# to water's K_w (the exact solution takes the compressibility in)
FLUID = {"bulk_modulus": 1.5e6, "density": 1000.0, "hydraulic_conductivity": 0.0025, "porosity": 0.5}


def consolidation_coefficient(fluid: dict = FLUID, skeleton: dict = SKELETON) -> float:
    """c_v = (k / (rho_w g_n)) / (1 / E_oed + n / K_w), E_oed = E for nu = 0."""
    mobility = fluid["hydraulic_conductivity"] / (fluid["density"] * G_N)
    return mobility / (1.0 / skeleton["youngs_modulus"] + fluid["porosity"] / fluid["bulk_modulus"])


def _factors(terms: int) -> np.ndarray:
    return np.pi * (2 * np.arange(terms) + 1) / 2


def terzaghi_pressure(depth: np.ndarray, tv: float, terms: int = 200) -> np.ndarray:
    """p / q at depth z below the drained top (200 terms: the tail is below exp(-(200 pi)^2 Tv))."""
    m = _factors(terms)[:, None]
    return np.sum(2 / m * np.sin(m * np.asarray(depth)[None, :] / HEIGHT) * np.exp(-m * m * tv), axis=0)


def terzaghi_degree(tv: float, terms: int = 2000) -> float:
    """U(Tv) = 1 - sum 2/M^2 exp(-M^2 Tv) (the tail of 2000 terms is below 1e-4 at Tv = 0)."""
    m = _factors(terms)
    return float(1 - np.sum(2 / m**2 * np.exp(-m * m * tv)))


def column_scene(cells: int, end: float, drained: bool = True, model: str = "drucker_prager",
                 fluid: dict = FLUID, dim: int = 2, damping: float | None = None, across: int = 1,
                 axisymmetric: bool = False, swelling: bool = False) -> dict:
    """The column, `cells` cells high and `across` wide (in 3D along x and y), 2 particles per cell
    and axis; `axisymmetric`: a cylinder of radius across h about the y axis. `swelling`: unloaded,
    from p = 0, its drained top held at p = q (see `consolidation`)."""
    h = HEIGHT / cells
    width = [across * h] * (dim - 1)
    vertical = "xyz"[dim - 1]
    upper = width + [HEIGHT]
    walls = [{"type": "wall", "face": f"{'xyz'[a]}{side}", "mode": "slip"} for a in range(dim) for side in "-+"
             if not (a == dim - 1 and side == "+")]
    conditions = walls + ([{"type": "pore_pressure", "face": f"{vertical}+", "pressure": LOAD if swelling else 0.0}]
                          if drained else [])
    scene = {
        "dimension": dim, "method": {"scheme": "musl", "shape_function": "linear"},
        "grid": {"lower": [0.0] * dim, "upper": upper, "cell_size": h},
        "materials": {"soil": {"model": model, **SKELETON, "pore_fluid": dict(fluid)}},
        "bodies": [{"name": "soil", "material": "soil", "particles_per_cell": 2,
                    "geometry": {"type": "box", "lower": [0.0] * dim, "upper": upper},
                    **({"initial_pore_pressure": {"type": "uniform", "pressure": LOAD}} if drained else {})}],
        "boundary_conditions": conditions,
        "loads": [{"type": "traction", "body": "soil",
                   "where": {"type": "box", "lower": [0.0] * (dim - 1) + [HEIGHT - h / 2], "upper": upper},
                   "traction": [0.0] * (dim - 1) + [-LOAD]}],
        "time": {"end": end, "cfl": 0.5},
        "output": {"frames": 2, "fields": ["pore_pressure", "effective_stress"]},
    }
    if model == "linear_elastic":   # (no strength keys)
        for key in ("friction_angle", "cohesion"):
            scene["materials"]["soil"].pop(key)
    if damping is not None:
        scene["damping"] = {"type": "local", "coefficient": damping}
    if axisymmetric:
        scene["axisymmetric"] = True
    if swelling:
        scene["loads"] = []
        del scene["bodies"][0]["initial_pore_pressure"]
    return scene


def run(scene: dict, until: float) -> ExplicitMPM:
    sim = ExplicitMPM(load_scene(scene))
    while sim.time < until * (1 - 1e-12):
        sim.advance(min(sim.stable_time_step(scene["time"]["cfl"]), until - sim.time))
    return sim


def consolidation(cells: int, tvs=(0.05, 0.197, 0.848), dim: int = 2, model: str = "drucker_prager",
                  swelling: bool = False, **shape) -> dict[float, tuple[float, float]]:
    """{Tv: (U measured, largest isochrone error max |p - p_exact| / q)}; U from the mean pore
    pressure, U = 1 - mean p / q (the volume-weighted mean: an axisymmetric column's rings differ).
    `swelling`: the unloaded column from p = 0 whose top is held at p = q takes the water in by the
    same diffusion (the total stress stays 0, sigma' = p), p_exact = q - Terzaghi's, U = mean p / q.
    `shape`: column_scene's `across` and `axisymmetric`."""
    cv = consolidation_coefficient()
    times = [tv * HEIGHT**2 / cv for tv in tvs]
    scene = column_scene(cells, end=times[-1], dim=dim, model=model, swelling=swelling, **shape)
    sim = ExplicitMPM(load_scene(scene))
    out = {}
    for tv, t in zip(tvs, times):
        while sim.time < t * (1 - 1e-12):
            sim.advance(min(sim.stable_time_step(0.5), t - sim.time))
        p = sim.particles.extra["pore_pressure"] / LOAD
        depth = HEIGHT - sim.particles.x[:, dim - 1]
        exact = terzaghi_pressure(depth, tv)
        mean = float(np.dot(sim.particles.volume, p) / np.sum(sim.particles.volume))
        measured = mean if swelling else 1 - mean
        error = float(np.max(np.abs(p - (1 - exact if swelling else exact))))
        out[tv] = (measured, error)
    return out


def seepage_to_hydrostatic(cells: int = 10, gravity_as_body_force: bool = False, tv: float = 2.5) -> np.ndarray:
    """The column unloaded, from p = 0, its top drained at p = 0, under g_n: the water flows until
    Darcy's flux vanishes, where grad p = rho_w g, i.e. p = rho_w g_n (H - z) (at Tv = 2.5 the
    consolidation's slowest mode is down to exp(-pi^2 Tv / 4) = 0.2 %). Gravity given as `gravity`
    or, `gravity_as_body_force`, as the scene's `body_force` (Darcy's law takes the step's whole body
    acceleration). Damped (local, 0.5): the skeleton settles under its own weight. Returns
    (p_p - rho_w g_n (H - z_p)) / (rho_w g_n H) for each particle."""
    end = tv * HEIGHT**2 / consolidation_coefficient()
    scene = column_scene(cells, end=end, damping=0.5)
    scene["loads"] = []
    del scene["bodies"][0]["initial_pore_pressure"]
    weight = [0.0] * (scene["dimension"] - 1) + [-G_N]
    scene["body_force" if gravity_as_body_force else "gravity"] = weight
    sim = run(scene, end)
    rho_g = FLUID["density"] * G_N
    depth = HEIGHT - sim.particles.x[:, scene["dimension"] - 1]
    return (sim.particles.extra["pore_pressure"] - rho_g * depth) / (rho_g * HEIGHT)


def undrained(fluid: dict, end: float, cells: int = 10, skeleton: dict | None = None,
              oedometric_modulus: float = SKELETON["youngs_modulus"]) -> tuple[float, float, float]:
    """(the water's share of the total vertical stress p / (p - sigma'_zz), the mean p / q, both over
    the particles below the top cell, and the exact share (K_w/n) / (K_w/n + E_oed)) of the sealed
    column loaded at t = 0 and damped to rest. The top cell is left out: the load reaches the grid
    through the top row of particles' stencils, so it carries 3/4 of q (a surface load's spread in MPM).
    `skeleton`: another soil material (with its E_oed) in place of the elastic Drucker-Prager one,
    started from its geostatic stress under a gravity of 1e-6 m/s^2 (a geostatic stress needs
    one; its weight is 1e-9 of the load)."""
    scene = column_scene(cells, end=end, drained=False, fluid=fluid, damping=0.5)
    if skeleton is not None:
        scene["materials"]["soil"] = {**skeleton, "pore_fluid": dict(fluid)}
        scene["bodies"][0]["initial_stress"] = {"type": "geostatic"}
        scene["gravity"] = [0.0] * (scene["dimension"] - 1) + [-1e-6]
    sim = run(scene, end)
    p = sim.particles.extra["pore_pressure"]
    dim = scene["dimension"]
    below = sim.particles.x[:, dim - 1] < HEIGHT - HEIGHT / cells
    effective = sim.particles.stress[below, dim - 1, dim - 1]
    share = float(np.mean(p[below] / (p[below] - effective)))
    storage = fluid["bulk_modulus"] / fluid["porosity"]
    return share, float(np.mean(p[below])) / LOAD, storage / (storage + oedometric_modulus)


WATER = {"bulk_modulus": 2.2e9, "density": 1000.0, "hydraulic_conductivity": 1.0e-8, "porosity": 0.5}


def isochrone_order(coarse: float, fine: float) -> float:
    return math.log2(coarse / fine)


def fast_wave_speed(fluid: dict = FLUID, skeleton: dict = SKELETON) -> float:
    """c = sqrt((K' + 4G/3 + K_w/n) / rho), rho the mixture density (the material's `density`):
    the undrained compression wave, the water moving with the skeleton."""
    e, nu = skeleton["youngs_modulus"], skeleton["poisson_ratio"]
    constrained = e * (1 - nu) / ((1 + nu) * (1 - 2 * nu))   # K' + 4G/3
    return math.sqrt((constrained + fluid["bulk_modulus"] / fluid["porosity"]) / skeleton["density"])


def _crossing_time(history: list[tuple[float, float]], level: float) -> float:
    """The time the pressure first reaches `level`, linear between the recorded steps."""
    for (t0, p0), (t1, p1) in zip(history, history[1:]):
        if p0 < level <= p1:
            return t0 + (t1 - t0) * (level - p0) / (p1 - p0)
    raise AssertionError(f"the pressure never reached {level:.4g}")


def fast_wave(cells: int, depths=(0.3, 0.7)) -> tuple[float, float, float]:
    """The sealed, undrained (k = 1e-8 m/s) column under a step load at its top: the times at
    which the pore pressure at two depths reaches half its undrained value behind the front,
    q (K_w/n) / (K_w/n + E_oed). Returns (measured speed (d2 - d1) / (t2 - t1), exact c, the
    front's spreading): the difference of two arrivals leaves out where the load enters (spread
    over the top particles' stencils). The spreading is how much longer the front takes to rise
    from 1/4 to 3/4 of its height at the deeper probe than at the other, over the transit time
    between them: the grid's dispersion widens the front as it travels, and its midpoint can
    drift from the characteristic by no more than that. The pressure at a depth is that of the
    particle nearest to it."""
    fluid = {**FLUID, "hydraulic_conductivity": 1.0e-8}
    c = fast_wave_speed(fluid)
    end = (max(depths) + 0.25 * HEIGHT) / c   # the front's tail past the deeper probe, before the base's echo
    scene = column_scene(cells, end=end, drained=False, fluid=fluid)
    sim = ExplicitMPM(load_scene(scene))
    dim = scene["dimension"]
    depth = HEIGHT - sim.particles.x[:, dim - 1]
    probes = [int(np.argmin(np.abs(depth - d))) for d in depths]
    probed = [float(depth[i]) for i in probes]
    storage = fluid["bulk_modulus"] / fluid["porosity"]
    half = 0.5 * LOAD * storage / (storage + SKELETON["youngs_modulus"])
    history = [(0.0, [0.0] * len(probes))]
    while sim.time < end * (1 - 1e-12):
        sim.advance(min(sim.stable_time_step(scene["time"]["cfl"]), end - sim.time))
        history.append((sim.time, [float(sim.particles.extra["pore_pressure"][i]) for i in probes]))
    def arrivals(level):
        return [_crossing_time([(t, p[j]) for t, p in history], level) for j in range(len(probes))]
    middle, early, late = arrivals(half), arrivals(0.5 * half), arrivals(1.5 * half)
    spreading = (late[1] - early[1]) - (late[0] - early[0])
    return (probed[1] - probed[0]) / (middle[1] - middle[0]), c, spreading * c / (probed[1] - probed[0])
