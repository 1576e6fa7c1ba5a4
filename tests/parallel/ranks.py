"""Scenes whose bodies cross slab boundaries, and running them on K processes the way users do."""
from __future__ import annotations

import copy
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

from solver.parallel import launch
from solver.results import read_frame

ELASTIC = {"model": "neo_hookean", "density": 1000, "youngs_modulus": 1000, "poisson_ratio": 0.3}

# Two disks 0.04 apart, closing at 1 m/s: they meet after 20 steps and are compressed
# for the remaining 180, each slab boundary is crossed by particles, and the slabs
# move (rebalance every 20 steps). Gravity, a slip floor and a prescribed-velocity
# box exercise body loads and constraints across slabs.
SCENE_2D = {
    "name": "equivalence-2d", "dimension": 2,
    "method": {"scheme": "musl", "transfer": "flip", "flip_ratio": 0.99},
    "grid": {"lower": [0.0, 0.0], "upper": [1.0, 0.5], "cell_size": 0.02},
    "materials": {"rubber": ELASTIC},
    "bodies": [
        {"name": "left", "material": "rubber", "particles_per_cell": 2, "initial_velocity": [0.5, 0.0],
         "geometry": {"type": "sphere", "center": [0.38, 0.25], "radius": 0.1}},
        {"name": "right", "material": "rubber", "particles_per_cell": 2, "initial_velocity": [-0.5, 0.0],
         "geometry": {"type": "sphere", "center": [0.62, 0.25], "radius": 0.1}},
    ],
    "boundary_conditions": [
        {"type": "wall", "face": "y-", "mode": "slip"},
        {"type": "velocity", "where": {"type": "box", "lower": [0.9, 0.0], "upper": [1.0, 0.5]}, "velocity": [0.0, None]},
    ],
    "gravity": [0.0, -1.0],
    "time": {"end": 0.2, "dt": 0.001},
    "output": {"frames": 2, "fields": ["position", "velocity", "stress"], "energies": 10},
    "parallel": {"processes": 1, "rebalance_every": 20},
}

# SCENE_2D with heat: the disks start at 400 and 300 K, conduct and expand, a box of nodes
# across the slab cuts is held at a rising temperature, and a floor slab across every
# slab takes a heat flux and convection through the face y- (solver/thermal.py).
HEAT_2D = {
    **copy.deepcopy(SCENE_2D), "name": "equivalence-heat",
    "materials": {"rubber": {**ELASTIC, "thermal_conductivity": 1.0e4, "specific_heat": 1000.0,
                             "thermal_expansion": 1.0e-3}},
    "output": {"frames": 2, "fields": ["position", "velocity", "stress", "temperature", "heat_flux"], "energies": 10},
}
HEAT_2D["bodies"][0]["initial_temperature"] = 400.0
HEAT_2D["bodies"][1]["initial_temperature"] = 300.0
HEAT_2D["bodies"].append({"name": "floor", "material": "rubber", "particles_per_cell": 2,
                          "geometry": {"type": "box", "lower": [0.04, 0.0], "upper": [0.96, 0.06]}})
HEAT_2D["boundary_conditions"] = SCENE_2D["boundary_conditions"] + [
    {"type": "temperature", "where": {"type": "box", "lower": [0.3, 0.2], "upper": [0.7, 0.24]},
     "temperature": "350 + 100 * t"},
    {"type": "heat_flux", "face": "y-", "flux": "1e5 * t"},
    {"type": "convection", "face": "y-", "coefficient": 100.0, "ambient": 250.0}]

# The same in 3D: two spheres on a 25 x 10 x 10 grid (about 1100 particles).
SCENE_3D = {
    **copy.deepcopy(SCENE_2D), "name": "equivalence-3d", "dimension": 3,
    "grid": {"lower": [0.0, 0.0, 0.0], "upper": [1.0, 0.4, 0.4], "cell_size": 0.04},
    "bodies": [
        {"name": "left", "material": "rubber", "particles_per_cell": 2, "initial_velocity": [0.5, 0.0, 0.0],
         "geometry": {"type": "sphere", "center": [0.38, 0.2, 0.2], "radius": 0.1}},
        {"name": "right", "material": "rubber", "particles_per_cell": 2, "initial_velocity": [-0.5, 0.0, 0.0],
         "geometry": {"type": "sphere", "center": [0.62, 0.2, 0.2], "radius": 0.1}},
    ],
    "boundary_conditions": [{"type": "wall", "face": "z-", "mode": "slip"}],
    "gravity": [0.0, 0.0, -1.0],
}

# A block on a slip floor squeezed by rigid bodies across the slabs (split along x): two
# platens on top moving down at different speeds, meeting at x = 0.52 (a slab boundary
# for K = 2), and a pusher on the right accelerating to the left. Where two bodies'
# cells share nodes the body seeded first keeps them (the left platen at x = 0.52, the
# right one over the pusher). The reactions are compared as well.
RIGID_2D = {
    **copy.deepcopy(SCENE_2D), "name": "equivalence-rigid",
    "grid": {"lower": [0.0, 0.0], "upper": [1.0, 0.4], "cell_size": 0.02},
    "materials": {"rubber": ELASTIC, "steel": {"model": "rigid", "density": 7800}},
    "bodies": [
        {"name": "block", "material": "rubber", "particles_per_cell": 2,
         "geometry": {"type": "box", "lower": [0.2, 0.0], "upper": [0.8, 0.2]}},
        {"name": "platen_left", "material": "steel", "particles_per_cell": 2, "velocity": [0.0, -0.1],
         "geometry": {"type": "box", "lower": [0.1, 0.2], "upper": [0.52, 0.24]}},
        {"name": "platen_right", "material": "steel", "particles_per_cell": 2, "velocity": [0.0, -0.12],
         "geometry": {"type": "box", "lower": [0.52, 0.2], "upper": [0.9, 0.24]}},
        {"name": "pusher", "material": "steel", "particles_per_cell": 2, "velocity": ["-0.5*t", None],
         "geometry": {"type": "box", "lower": [0.8, 0.0], "upper": [0.84, 0.2]}},
    ],
    "boundary_conditions": [{"type": "wall", "face": "y-", "mode": "slip"}],
}

# Billet upsetting (tests/verification/billet.py, scaled down): an axisymmetric J2 steel
# cylinder compressed by a rigid platen at 50 m/s. The grid has more cells along r than z,
# so the slabs split the radius: the hoop terms take r_I from whole-grid node layers.
AXISYMMETRIC = {
    "name": "equivalence-axisymmetric", "dimension": 2, "axisymmetric": True,
    "method": {"scheme": "musl", "transfer": "flip", "flip_ratio": 0.99},
    "grid": {"lower": [0.0, 0.0], "upper": [0.02, 0.018], "cell_size": 0.001},
    "materials": {"steel": {"model": "j2_plasticity", "density": 7800.0, "youngs_modulus": 200e9,
                            "poisson_ratio": 0.3, "yield_stress": 0.7e9, "hardening_modulus": 0.3e9},
                  "platen": {"model": "rigid", "density": 7800.0}},
    "bodies": [
        {"name": "billet", "material": "steel", "particles_per_cell": 2,
         "geometry": {"type": "box", "lower": [0.0, 0.0], "upper": [0.01, 0.015]}},
        {"name": "platen", "material": "platen", "particles_per_cell": 1, "velocity": [0.0, -50.0],
         "geometry": {"type": "box", "lower": [0.0, 0.015], "upper": [0.019, 0.017]}},
    ],
    "boundary_conditions": [{"type": "wall", "face": "y-", "mode": "slip"}],
    "time": {"end": 200 * 5e-8, "dt": 5e-8},
    "output": {"frames": 2, "fields": ["position", "velocity", "stress"], "energies": 10},
    "parallel": {"processes": 1, "rebalance_every": 20},
}

# A saturated column (solver/pore_fluid.py) under a load at its top, drained there and through
# a box of nodes on its left side at mid-height: the slabs split its height (20 cells; the cut
# of K = 2 at y = 0.5, inside the box), so the storage, the nodal pressure, Darcy's inflow and
# the skeleton's volume change cross the halo, as do held nodes. K_w / n = 3 E and k as in
# tests/verification/pore_fluid_cases.py's Terzaghi column; dt under the diffusion limit (8e-4).
PORE_2D = {
    "name": "equivalence-pore", "dimension": 2, "method": {"scheme": "musl"},
    "grid": {"lower": [0.0, 0.0], "upper": [0.2, 1.0], "cell_size": 0.05},
    "materials": {"soil": {"model": "drucker_prager", "density": 2000.0, "youngs_modulus": 1.0e6,
                           "poisson_ratio": 0.3, "friction_angle": 30.0, "cohesion": 1.0e5,
                           "pore_fluid": {"bulk_modulus": 1.5e6, "density": 1000.0, "hydraulic_conductivity": 0.0025,
                                          "porosity": 0.5}}},
    "bodies": [{"name": "soil", "material": "soil", "particles_per_cell": 2,
                "geometry": {"type": "box", "lower": [0.0, 0.0], "upper": [0.2, 1.0]},
                "initial_pore_pressure": {"type": "uniform", "pressure": 1.0e4}}],
    "boundary_conditions": [{"type": "wall", "face": face, "mode": "slip"} for face in ("x-", "x+", "y-")] + [
        {"type": "pore_pressure", "face": "y+", "pressure": 0.0},
        {"type": "pore_pressure", "where": {"type": "box", "lower": [0.0, 0.44], "upper": [0.01, 0.56]},
         "pressure": "2e3 * t"}],
    "loads": [{"type": "traction", "body": "soil", "where": {"type": "box", "lower": [0.0, 0.975], "upper": [0.2, 1.0]},
               "traction": [0.0, -1.0e4]}],
    "time": {"end": 200 * 4e-4, "dt": 4e-4},
    "output": {"frames": 2, "fields": ["position", "velocity", "stress", "pore_pressure"], "energies": 10},
    "parallel": {"processes": 1, "rebalance_every": 20},
}

# Total Lagrangian (slabs of the reference configuration, particles never migrate):
# a block contracting along x under gravity, quadratic B-splines with APIC, and a
# rigid pusher that moves two cells to the left through the reference grid.
TLMPM_2D = {
    **copy.deepcopy(RIGID_2D), "name": "equivalence-tlmpm",
    "method": {"formulation": "tlmpm", "scheme": "musl", "shape_function": "quadratic_bspline",
               "transfer": "apic"},
    "bodies": [
        {"name": "block", "material": "rubber", "particles_per_cell": 2, "initial_velocity": ["0.5*(0.5 - x)", 0.0],
         "geometry": {"type": "box", "lower": [0.2, 0.02], "upper": [0.8, 0.2]}},
        {"name": "pusher", "material": "steel", "particles_per_cell": 2, "velocity": ["-2*t", None],
         "geometry": {"type": "box", "lower": [0.84, 0.02], "upper": [0.88, 0.2]}},
    ],
}


# A 2D shock tube across the slabs: a gas at 10 times the pressure on the left of x = 0.5
# expands into the right, in a closed box; linear hats, so that the gas takes its density
# from the grid (solver/gas_density.py): nodal masses summed across the slab cuts. The
# contact and the shock cross the cuts, which move (rebalance every 20 steps).
GAS_2D = {
    "name": "equivalence-gas", "dimension": 2, "method": {"scheme": "musl", "shape_function": "linear"},
    "grid": {"lower": [0.0, 0.0], "upper": [1.0, 0.2], "cell_size": 0.02},
    "materials": {"air": {"model": "ideal_gas"}},
    "bodies": [
        {"name": "high", "material": "air", "particles_per_cell": 2, "initial_density": 1.0, "initial_pressure": 1.0,
         "geometry": {"type": "box", "lower": [0.0, 0.0], "upper": [0.5, 0.2]}},
        {"name": "low", "material": "air", "particles_per_cell": 2, "initial_density": 0.125,
         "initial_pressure": 0.1, "geometry": {"type": "box", "lower": [0.5, 0.0], "upper": [1.0, 0.2]}},
    ],
    "boundary_conditions": [{"type": "wall", "face": face, "mode": "slip"} for face in ("x-", "x+", "y-", "y+")],
    "time": {"end": 0.1, "dt": 0.0005},
    "output": {"frames": 2, "fields": ["position", "velocity", "stress", "density"], "energies": 10},
    "parallel": {"processes": 1, "rebalance_every": 20},
}


def scene(base: dict, **changes) -> dict:
    out = copy.deepcopy(base)
    for path, value in changes.items():
        target = out
        *parents, last = path.split("__")
        for key in parents:
            target = target[key]
        target[last] = value
    return out


def run_cli(scene: dict, out: Path, processes: int, timeout: float = 300) -> subprocess.CompletedProcess:
    """`mpm run -n K` (python -m solver run): the command launches its own ranks."""
    out.mkdir(parents=True, exist_ok=True)
    path = out / "scene.json"
    path.write_text(json.dumps(scene))
    return subprocess.run([sys.executable, "-m", "solver", "run", str(path), "-o", str(out), "-n", str(processes),
                           "--progress", "none"], capture_output=True, text=True, timeout=timeout)


def run_mpiexec(scene: dict, out: Path, processes: int, timeout: float = 300) -> subprocess.CompletedProcess:
    """`mpiexec -n K python -m mpi4py -m solver run ...` started here, as a cluster job script would."""
    out.mkdir(parents=True, exist_ok=True)
    path = out / "scene.json"
    path.write_text(json.dumps(scene))
    command = launch.command(processes, ["run", str(path), "-o", str(out), "--progress", "none"])
    return subprocess.run(command, capture_output=True, text=True, timeout=timeout, env=launch.environment())


def last_frame(out: Path) -> dict:
    return read_frame(out / "result.h5", -1)


def relative_difference(a: np.ndarray, b: np.ndarray) -> float:
    """max |a - b| / max |a|: the error relative to the field's scale."""
    return float(np.max(np.abs(a - b)) / np.max(np.abs(a)))
