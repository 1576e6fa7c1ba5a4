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
The splat is the powder's largest connected piece (`splat_particles`): at 800 m/s the
example's jet sheds a fully damaged particle that flies off at 500 m/s, and it would otherwise
set D. d0 and the substrate's original top are read from the scene, so the measures hold for the
scaled scenes of `impact` (another speed, another powder size) too.
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


def _scale_geometry(geometry: dict, factor: float) -> None:
    for key in ("center", "lower", "upper"):
        if key in geometry:
            geometry[key] = [factor * v for v in geometry[key]]
    for key in ("radius", "height"):
        if key in geometry:
            geometry[key] *= factor
    for part in geometry.get("parts", ()):
        _scale_geometry(part, factor)


def impact(scene: dict, speed: float = SPEED, size: float = 1.0) -> dict:
    """A cold-spray scene at another impact speed and powder size: `size` multiplies every
    length (the grid's bounds and cell size, every body's geometry: powder and substrate) and
    the end time, so the scene is the same in cells and in steps; `speed` sets the powder's
    initial velocity. The impact lasts about d0 / v, so below SPEED the end time grows by
    SPEED / speed (at 400 m/s: 90 ns x size); at and above SPEED it stays 60 ns x size.
    The number of output frames is kept. Copper without conduction has no length of its own:
    in the continuum equations x -> s x, t -> s t at the same speed leaves everything the same
    except Johnson-Cook's strain-rate terms (the rates ~ v / d0 fall by s)."""
    scene = copy.deepcopy(scene)
    grid = scene["grid"]
    grid["lower"] = [size * v for v in grid["lower"]]
    grid["upper"] = [size * v for v in grid["upper"]]
    grid["cell_size"] *= size
    for body in scene["bodies"]:
        _scale_geometry(body["geometry"], size)
    velocity = scene["bodies"][POWDER]["initial_velocity"]
    scene["bodies"][POWDER]["initial_velocity"] = [0.0] * (len(velocity) - 1) + [-float(speed)]
    scene["time"]["end"] *= size * max(1.0, SPEED / speed)
    return scene


def powder_diameter(scene: dict) -> float:
    """d0: twice the radius of the powder's sphere."""
    parts = scene["bodies"][POWDER]["geometry"]["parts"]
    return 2.0 * next(p["radius"] for p in parts if p["type"] == "sphere")


def _top(geometry: dict, axis: int) -> float:
    kind = geometry["type"]
    if kind == "box":
        return geometry["upper"][axis]
    if kind == "cylinder" and geometry["axis"] == axis:
        return geometry["center"][axis] + 0.5 * geometry["height"]
    if kind == "intersection":
        return min(_top(part, axis) for part in geometry["parts"] if part["type"] in ("box", "cylinder", "intersection"))
    raise ValueError(f"no top for a {kind}")


def substrate_top(scene: dict) -> float:
    """The substrate's original top: its box's (the 3D quarter's: the box's and the cylinder's)."""
    return _top(scene["bodies"][SUBSTRATE]["geometry"], scene["dimension"] - 1)


def particle_spacing(scene: dict, body: int) -> float:
    return scene["grid"]["cell_size"] / scene["bodies"][body]["particles_per_cell"]


def splat_particles(radial: np.ndarray, axial: np.ndarray, cell: float) -> np.ndarray:
    """Which of these particles form the largest connected piece: the particles binned into
    cells of side `cell` in the (radial, axial) plane, cells joined to their 8 neighbours; the
    piece with the most particles. A particle two cells or more from all the others is not in it."""
    cells: dict[tuple[int, int], list[int]] = {}
    for k, key in enumerate(zip(np.floor(radial / cell).astype(int).tolist(), np.floor(axial / cell).astype(int).tolist())):
        cells.setdefault(key, []).append(k)
    seen: set[tuple[int, int]] = set()
    best: list[int] = []
    for start in cells:
        if start in seen:
            continue
        seen.add(start)
        stack, members = [start], []
        while stack:
            a, b = stack.pop()
            members.extend(cells[(a, b)])
            for near in ((a + da, b + db) for da in (-1, 0, 1) for db in (-1, 0, 1)):
                if near in cells and near not in seen:
                    seen.add(near)
                    stack.append(near)
        if len(members) > len(best):
            best = members
    keep = np.zeros(len(radial), dtype=bool)
    keep[best] = True
    return keep


def splat_measures(frame: dict, scene: dict) -> dict:
    """D / d0, h / d0 (of the splat), crater depth / d0, the powder's mass fraction not in the
    splat, and the peak temperatures and plastic strain of a frame."""
    f = frame["fields"]
    dim = scene["dimension"]
    x = f["position"]
    radial = x[:, 0] if dim == 2 else np.hypot(x[:, 0], x[:, 1])
    axial = x[:, dim - 1]
    powder, substrate = f["body"] == POWDER, f["body"] == SUBSTRATE
    splat = np.zeros_like(powder)
    splat[powder] = splat_particles(radial[powder], axial[powder], scene["grid"]["cell_size"])
    half_p = 0.5 * particle_spacing(scene, POWDER)
    half_s = 0.5 * particle_spacing(scene, SUBSTRATE)
    d0 = powder_diameter(scene)
    # on the axis: within one cell of it (the measures' resolution). The substrate's surface is
    # its highest particle there: in the 3D quarter the particle column on the edge where the
    # two symmetry planes meet sinks 3 um deeper than its neighbours (both 3D runs; cause not
    # investigated) and would otherwise set the crater.
    on_axis = radial < scene["grid"]["cell_size"]
    surface_on_axis = axial[substrate & on_axis].max() + half_s
    powder_top_on_axis = axial[splat & on_axis].max() + half_p
    return {
        "flattening": 2.0 * (radial[splat].max() + half_p) / d0,
        "height": (powder_top_on_axis - surface_on_axis) / d0,
        "crater": (substrate_top(scene) - surface_on_axis) / d0,
        "T_powder": float(np.nanmax(f["temperature"][powder])),
        "T_substrate": float(np.nanmax(f["temperature"][substrate])),
        "plastic_strain": float(f["plastic_strain"].max()),
        "ejected": float(f["mass"][powder & ~splat].sum() / f["mass"][powder].sum()),   # mass fraction off the splat
        "powder_velocity": float((f["mass"][powder] * f["velocity"][powder, dim - 1]).sum() / f["mass"][powder].sum()),
    }


def plastic_work(frame: dict, scene: dict) -> float:
    """The plastic work done so far, from the adiabatic temperature rise: Johnson-Cook heats by
    taylor_quinney x the plastic work, m c dT per particle (valid without conduction)."""
    copper = scene["materials"]["copper"]
    f = frame["fields"]
    rise = f["temperature"] - copper["room_temperature"]
    return float((f["mass"] * copper["specific_heat"] * rise).sum() / copper["taylor_quinney"])
