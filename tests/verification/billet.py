"""Billet upsetting with a rigid platen ([K] 4.2, [R] Appendix G; VERIFICATION_CASES E16).

A steel cylinder (20 mm diameter, 30 mm high; E = 200 GPa, nu = 0.3, rho = 7800,
yield 0.7 GPa, linear hardening 0.3 GPa) is compressed by a rigid platen that sticks
to it. Half the height is modelled (mid-plane symmetry: a slip wall at y = 0); in 3D a
quarter of the cross-section (slip walls on x = 0 and z = 0). The platen moves at
`speed` (the source's 1 m/s needs ~10^5 steps per 50 %; 10 m/s keeps the loading
quasi-static: a wave crosses the half billet in 2.5 us, the loading lasts 150 us or more).
The load is the platen's reaction (series reaction_platen_y), x 4 in 3D for the quarter.
"""
from __future__ import annotations

R, HALF_HEIGHT = 10e-3, 15e-3
STEEL = {"model": "j2_plasticity", "density": 7800.0, "youngs_modulus": 200e9, "poisson_ratio": 0.3,
         "yield_stress": 0.7e9, "hardening_modulus": 0.3e9}


def billet_scene(dimension: int, cell: float = 1e-3, speed: float = 10.0, strain: float = 0.5,
                 ppc: int = 2, frames: int = 11) -> dict:
    top = HALF_HEIGHT + 2 * cell
    velocity = [0.0] * dimension
    velocity[1] = -speed
    if dimension == 2:
        grid = {"lower": [0.0, 0.0], "upper": [2.0 * R, top + cell], "cell_size": cell}
        billet = {"type": "box", "lower": [0.0, 0.0], "upper": [R, HALF_HEIGHT]}
        platen = {"type": "box", "lower": [0.0, HALF_HEIGHT], "upper": [1.9 * R, top]}
        walls = ["y-"]
    else:
        grid = {"lower": [0.0, 0.0, 0.0], "upper": [2.0 * R, top + cell, 2.0 * R], "cell_size": cell}
        billet = {"type": "intersection", "parts": [
            {"type": "cylinder", "center": [0.0, HALF_HEIGHT / 2, 0.0], "radius": R, "axis": 1, "height": HALF_HEIGHT},
            {"type": "box", "lower": [0.0, 0.0, 0.0], "upper": [R, HALF_HEIGHT, R]}]}
        platen = {"type": "box", "lower": [0.0, HALF_HEIGHT, 0.0], "upper": [1.9 * R, top, 1.9 * R]}
        walls = ["y-", "x-", "z-"]
    return {
        "name": f"Billet upsetting, rigid platen (E16), {'axisymmetric' if dimension == 2 else '3D quarter'}",
        "dimension": dimension, "axisymmetric": dimension == 2,
        "method": {"formulation": "ulmpm", "scheme": "musl", "shape_function": "linear", "transfer": "flip",
                   "flip_ratio": 0.99},
        "grid": grid,
        "materials": {"steel": STEEL, "platen": {"model": "rigid", "density": 7800.0}},
        # one particle per cell marks every cell the platen covers
        "bodies": [{"name": "billet", "material": "steel", "particles_per_cell": ppc, "geometry": billet},
                   {"name": "platen", "material": "platen", "particles_per_cell": 1, "geometry": platen,
                    "velocity": velocity}],
        "boundary_conditions": [{"type": "wall", "face": face, "mode": "slip"} for face in walls],
        "time": {"end": strain * HALF_HEIGHT / speed, "cfl": 0.5},
        "output": {"frames": frames, "fields": ["position", "velocity", "stress", "plastic_strain"],
                   "preview": {"field": "plastic_strain"}},
    }
