"""Cold spray (E17, [K] 4.3): the splat and the crater of every variant, side by side.

    python benchmarks/cold_spray.py [--out DIR] [--only KEY ...] [--threads N]
    python benchmarks/cold_spray.py --trends [--resolution coarse|example|both] [--out DIR]

Runs examples/cold_spray_axisymmetric.json and examples/cold_spray_3d_quarter.json with the
single velocity field (the default) and with the per-body contact ("friction", mu = 0: the
frictionless contact [K] describes), and the axisymmetric single-field case with heat
conduction in copper (issue 16) beside the adiabatic run. Prints the table of
docs/benchmarks.md (flattening ratio D / d0, height ratio h / d0, crater depth / d0, peak
temperatures, the powder's final velocity, energy, steps, particles, wall time) and draws
docs/images/cold_spray_shapes.png (final shapes coloured by plastic strain and by temperature)
and docs/images/cold_spray_conduction.png (adiabatic against conducting).
--trends runs the axisymmetric scene at 400-800 m/s and with the powder twice as large
(d0 = 40 um, every length and the end time doubled) at 600 m/s, single field and contact,
on the coarse scene of the tests (2 um cells) and the example's (1 um), and prints the table
of docs/benchmarks.md's "Against published trends" (tests/verification/cold_spray.py, `impact`).
Results are kept in DIR (default a temporary folder); a variant whose result.h5 is already
complete there is read, not run again (--rerun runs everything).
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests" / "verification"))

from cold_spray import SUBSTRATE_TOP, coarse_axisymmetric, impact, plastic_work, splat_measures, variant  # noqa: E402

from solver import run  # noqa: E402
from solver.results import list_frames, read_frame, read_series  # noqa: E402

VARIANTS = {   # key: (label, dimension, contact, conduction)
    "axi_single": ("axisymmetric, single field", 2, "single_field", False),
    "axi_friction": ("axisymmetric, contact (mu = 0)", 2, "friction", False),
    "axi_conduction": ("axisymmetric, single field, conduction", 2, "single_field", True),
    "q3d_single": ("3D quarter, single field", 3, "single_field", False),
    "q3d_friction": ("3D quarter, contact (mu = 0)", 3, "friction", False),
}


def kept_run(scene: dict, folder: Path, threads: int, rerun: bool) -> tuple[Path, float]:
    """The result file of the scene run into `folder` (run now unless kept there already, or
    `rerun`) and the run's wall time (NaN for a kept run that recorded none)."""
    scene.setdefault("parallel", {})["threads"] = threads
    result_file, wall_file = folder / "result.h5", folder / "wall_seconds"
    if rerun or not result_file.exists():
        start = time.perf_counter()
        result = run(scene, folder)
        wall = time.perf_counter() - start
        if result.status != "complete":
            raise SystemExit(f"{folder.name}: {result.status}: {result.message}")
        wall_file.write_text(f"{wall}\n")
    return result_file, float(wall_file.read_text()) if wall_file.exists() else float("nan")


def run_variant(key: str, out: Path, threads: int, rerun: bool) -> dict:
    label, dim, contact, conduction = VARIANTS[key]
    scene = variant(dim, contact, conduction)
    result_file, wall = kept_run(scene, out / key, threads, rerun)
    series = read_series(result_file)
    final = read_frame(result_file, -1)
    measures = splat_measures(final, scene)
    peaks = [splat_measures(read_frame(result_file, frame["index"]), scene) for frame in list_frames(result_file)]
    measures["T_powder_peak"] = max(p["T_powder"] for p in peaks)     # with conduction the peak can pass
    measures["T_substrate_peak"] = max(p["T_substrate"] for p in peaks)
    kinetic0 = series["kinetic_energy"][0]
    measures |= {
        "label": label, "scene": scene, "final": final, "wall": wall,
        "steps": len(series["time"]) - 1, "particles": len(final["fields"]["mass"]),
        "kinetic_end": series["kinetic_energy"][-1] / kinetic0,
        "closure": (plastic_work(final, scene) + series["total_energy"][-1]) / kinetic0 if not conduction else None,
    }
    return measures


def print_table(rows: dict) -> None:
    print("| variant | D / d0 | h / d0 | crater / d0 | T peak powder (K) | T peak substrate (K) | T end substrate (K) | max eps_p | "
          "powder v_z end (m/s) | KE end / KE0 | (W_p + KE + SE) / KE0 | steps | particles | wall (s) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows.values():
        closure = "" if r["closure"] is None else f"{r['closure']:.3f}"
        print(f"| {r['label']} | {r['flattening']:.2f} | {r['height']:.2f} | {r['crater']:.2f} | {r['T_powder_peak']:.0f} | "
              f"{r['T_substrate_peak']:.0f} | {r['T_substrate']:.0f} | {r['plastic_strain']:.2f} | {r['powder_velocity']:+.1f} | "
              f"{r['kinetic_end']:.4f} | {closure} | {r['steps']} | {r['particles']} | {r['wall']:.0f} |", flush=True)


def section(r: dict):
    """The particles of a final frame in the plane of the axis (the 3D quarter's y ~ 0 layer), in um."""
    f = r["final"]["fields"]
    x = f["position"]
    if r["scene"]["dimension"] == 2:
        keep = slice(None)
        return x[:, 0] * 1e6, x[:, 1] * 1e6, f, keep
    spacing = r["scene"]["grid"]["cell_size"] / r["scene"]["bodies"][0]["particles_per_cell"]
    keep = x[:, 1] < spacing
    return x[keep, 0] * 1e6, x[keep, 2] * 1e6, f, keep


def draw(rows: dict, fields: tuple[str, ...], path: Path, title: str) -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    keys = list(rows)
    fig, axes = plt.subplots(len(fields), len(keys), figsize=(3.2 * len(keys), 3.0 * len(fields)), squeeze=False)
    limits = {"plastic_strain": (0.0, 3.0), "temperature": (298.0, 700.0)}
    names = {"plastic_strain": "plastic strain", "temperature": "temperature (K)"}
    for col, key in enumerate(keys):
        r, (radial, axial, f, keep) = rows[key], section(rows[key])
        for row, field in enumerate(fields):
            ax = axes[row][col]
            dots = ax.scatter(radial, axial, c=f[field][keep], s=1.5, cmap="inferno", vmin=limits[field][0],
                              vmax=limits[field][1], linewidths=0)
            ax.axhline(SUBSTRATE_TOP * 1e6, color="0.6", lw=0.5, ls="--")
            ax.set_xlim(0, 25)
            ax.set_ylim(15, 37)
            ax.set_aspect("equal")
            ax.set_title(f"{r['label']}\n{names[field]}" if row == 0 else names[field], fontsize=7)
            ax.tick_params(labelsize=6)
            fig.colorbar(dots, ax=ax, shrink=0.7).ax.tick_params(labelsize=6)
    fig.suptitle(title, fontsize=9)
    fig.tight_layout()
    fig.savefig(path, dpi=130)
    print(f"wrote {path}")


TREND_SPEEDS = (400.0, 500.0, 600.0, 700.0, 800.0)
TREND_GRID_TOP = 1.0e-4      # x size: at 700-800 m/s with the contact a particle shed by the jet left the 52 um grid


def trend_scene(resolution: str, contact: str, speed: float, size: float) -> dict:
    """The axisymmetric scene at `speed` and `size` (the powder's diameter over 20 um), its grid
    raised to 100 um x size: particles shed by the rim's jet stay on it (empty cells above change
    nothing else: the 600 m/s runs give the same numbers on either grid)."""
    base = coarse_axisymmetric(contact) if resolution == "coarse" else variant(2, contact)
    scene = impact(base, speed, size)
    scene["grid"]["upper"][1] = TREND_GRID_TOP * size
    return scene


def run_trend(resolution: str, contact: str, speed: float, size: float, out: Path, threads: int, rerun: bool) -> dict:
    scene = trend_scene(resolution, contact, speed, size)
    result_file, wall = kept_run(scene, out / f"trend_{resolution}_{contact}_{speed:.0f}_{size:g}", threads, rerun)
    series = read_series(result_file)
    final = read_frame(result_file, -1)
    peaks = [splat_measures(read_frame(result_file, frame["index"]), scene) for frame in list_frames(result_file)]
    measures = splat_measures(final, scene)
    return measures | {
        "resolution": resolution, "contact": contact, "speed": speed, "d0": 20.0 * size,
        "T_powder_peak": max(p["T_powder"] for p in peaks), "T_substrate_peak": max(p["T_substrate"] for p in peaks),
        "kinetic_end": series["kinetic_energy"][-1] / series["kinetic_energy"][0],
        "steps": len(series["time"]) - 1, "wall": wall,
    }


def trends(resolutions: list[str], out: Path, threads: int, rerun: bool) -> None:
    """The speed series and the size pair, printed as one table."""
    names = {"single_field": "single field", "friction": "contact (mu = 0)"}
    cells = {"coarse": "2 um cells", "example": "1 um cells"}
    print("| scene | contact | v (m/s) | d0 (um) | D / d0 | h / d0 | 1 - h / d0 | crater / d0 | T peak powder (K) | "
          "T peak substrate (K) | max eps_p | KE end / KE0 | mass shed | steps | wall (s) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for resolution in resolutions:
        for contact in ("single_field", "friction"):
            for speed, size in [(v, 1.0) for v in TREND_SPEEDS] + [(600.0, 2.0)]:
                r = run_trend(resolution, contact, speed, size, out, threads, rerun)
                print(f"| {cells[resolution]} | {names[contact]} | {speed:.0f} | {r['d0']:.0f} | {r['flattening']:.3f} | "
                      f"{r['height']:.3f} | {1.0 - r['height']:.3f} | {r['crater']:.3f} | {r['T_powder_peak']:.0f} | "
                      f"{r['T_substrate_peak']:.0f} | {r['plastic_strain']:.2f} | {r['kinetic_end']:.4f} | "
                      f"{r['ejected']:.4f} | {r['steps']} | {r['wall']:.1f} |", flush=True)


def main() -> int:
    parser = argparse.ArgumentParser()
    parser.add_argument("--out", type=Path)
    parser.add_argument("--only", nargs="*", choices=list(VARIANTS))
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--rerun", action="store_true")
    parser.add_argument("--trends", action="store_true", help="the speed series and the size pair (no images)")
    parser.add_argument("--resolution", choices=("coarse", "example", "both"), default="both")
    args = parser.parse_args()
    out = args.out or Path(tempfile.mkdtemp(prefix="cold_spray_"))
    if args.trends:
        trends(["coarse", "example"] if args.resolution == "both" else [args.resolution], out, args.threads, args.rerun)
        return 0
    keys = args.only or list(VARIANTS)
    rows = {key: run_variant(key, out, args.threads, args.rerun) for key in keys}
    print_table(rows)
    images = ROOT / "docs" / "images"
    shapes = [k for k in ("axi_single", "axi_friction", "q3d_single", "q3d_friction") if k in rows]
    if shapes:
        draw({k: rows[k] for k in shapes}, ("plastic_strain", "temperature"), images / "cold_spray_shapes.png",
             "Cold spray, Cu on Cu at 600 m/s, t = 60 ns (3D: the particles on the symmetry plane y = 0)")
    if "axi_single" in rows and "axi_conduction" in rows:
        draw({k: rows[k] for k in ("axi_single", "axi_conduction")}, ("temperature", "plastic_strain"),
             images / "cold_spray_conduction.png", "Adiabatic against conduction (k = 401 W/(m K)), t = 60 ns")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
