"""E17, cold spray ([K] 4.3): the example scenes, their variants and the splat's measures.

A copper sphere of radius R = 10 um hits a copper substrate (8 R across, 3 R high) at 600 m/s;
examples/cold_spray_axisymmetric.json and examples/cold_spray_3d_quarter.json are the two
models of [K] Fig. 11. Used by tests/verification/test_cold_spray.py and benchmarks/cold_spray.py.

Measures of the final shape (d0 = 2 R, the powder's diameter), the usual ones of the
cold-spray literature:
- flattening ratio D / d0: the splat's largest diameter over the powder's diameter;
- height ratio h / d0: the splat's thickness on the axis of impact (from the crater's floor
  to the powder's top) over the powder's diameter (the jet at the rim rises higher);
- crater depth: how far below the substrate's original top the substrate's surface on the
  axis of impact ends, over d0.
Particle centres sit half a particle spacing inside the body's surface: each extent is the
extreme centres plus that half spacing, so the measures of the undeformed bodies are exact.
"""
from __future__ import annotations

import copy
import json
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = {2: ROOT / "examples" / "cold_spray_axisymmetric.json", 3: ROOT / "examples" / "cold_spray_3d_quarter.json"}
RADIUS = 1.0e-5
SUBSTRATE_TOP = 3.0e-5
SPEED = 600.0
SUBSTRATE, POWDER = 0, 1                 # body indices, in the examples' order
COPPER_CONDUCTIVITY = 401.0              # W/(m K), pure copper at room temperature


def example_scene(dim: int) -> dict:
    return json.loads(EXAMPLES[dim].read_text())


def variant(dim: int, contact: str = "single_field", conduction: bool = False, frames: int | None = None) -> dict:
    """An example with the powder/substrate contact `contact` ("single_field": one velocity
    field, the bodies stick where they touch; "friction": a field per body, mu = 0, the
    frictionless contact [K] describes) and, with `conduction`, copper's conductivity."""
    scene = example_scene(dim)
    if contact != "single_field":
        scene["contact"] = {"model": contact}
    if conduction:
        scene["materials"]["copper"]["thermal_conductivity"] = COPPER_CONDUCTIVITY
    if frames is not None:
        scene["output"]["frames"] = frames
    return scene


def coarse_axisymmetric(contact: str = "single_field") -> dict:
    """The axisymmetric example on cells twice as large with 2 x 2 particles per cell (20 x 26
    cells, 1564 particles): the same geometry, the powder still one cell above the substrate."""
    scene = variant(2, contact, frames=7)
    scene["grid"]["cell_size"] = 2.0e-6
    for body in scene["bodies"]:
        body["particles_per_cell"] = 2
    powder = scene["bodies"][POWDER]["geometry"]["parts"]
    powder[0]["center"][1] = 4.2e-5       # bottom at 32 um: one empty cell (30-32 um) to the substrate
    powder[1]["lower"][1] = 3.2e-5
    return copy.deepcopy(scene)


def particle_spacing(scene: dict, body: int) -> float:
    return scene["grid"]["cell_size"] / scene["bodies"][body]["particles_per_cell"]


def splat_measures(frame: dict, scene: dict) -> dict:
    """D / d0, h / d0, crater depth / d0 and the peak temperatures and plastic strain of a frame."""
    f = frame["fields"]
    dim = scene["dimension"]
    x = f["position"]
    radial = x[:, 0] if dim == 2 else np.hypot(x[:, 0], x[:, 1])
    axial = x[:, dim - 1]
    powder, substrate = f["body"] == POWDER, f["body"] == SUBSTRATE
    half_p = 0.5 * particle_spacing(scene, POWDER)
    half_s = 0.5 * particle_spacing(scene, SUBSTRATE)
    d0 = 2.0 * RADIUS
    # on the axis: within one cell of it (the measures' resolution). The substrate's surface is
    # its highest particle there: in the 3D quarter the particle column on the edge where the
    # two symmetry planes meet sinks 3 um deeper than its neighbours (both 3D runs; cause not
    # investigated) and would otherwise set the crater.
    on_axis = radial < scene["grid"]["cell_size"]
    surface_on_axis = axial[substrate & on_axis].max() + half_s
    powder_top_on_axis = axial[powder & on_axis].max() + half_p
    return {
        "flattening": 2.0 * (radial[powder].max() + half_p) / d0,
        "height": (powder_top_on_axis - surface_on_axis) / d0,
        "crater": (SUBSTRATE_TOP - surface_on_axis) / d0,
        "T_powder": float(np.nanmax(f["temperature"][powder])),
        "T_substrate": float(np.nanmax(f["temperature"][substrate])),
        "plastic_strain": float(f["plastic_strain"].max()),
        "powder_velocity": float((f["mass"][powder] * f["velocity"][powder, dim - 1]).sum() / f["mass"][powder].sum()),
    }


def plastic_work(frame: dict, scene: dict) -> float:
    """The plastic work done so far, from the adiabatic temperature rise: Johnson-Cook heats by
    taylor_quinney x the plastic work, m c dT per particle (valid without conduction)."""
    copper = scene["materials"]["copper"]
    f = frame["fields"]
    rise = f["temperature"] - copper["room_temperature"]
    return float((f["mass"] * copper["specific_heat"] * rise).sum() / copper["taylor_quinney"])
