"""Preview images (PNG) of one frame of a result file.

Particles are drawn coloured by one scalar per particle:

* a per-particle scalar dataset as it is (``mass``, ``von_mises``, ``id``, ...);
* a vector dataset (``velocity``, ``position``) by its magnitude;
* a Voigt tensor dataset (``stress``, 6 columns) by its von Mises value;
* ``velocity_magnitude``, ``von_mises`` and ``pressure`` are derived from
  ``velocity`` / ``stress`` when the frame does not store them.

1D scenes plot the value against x; 2D scenes are a scatter in the x-y plane;
3D scenes are a perspective scatter with y drawn upwards (the axis gravity
usually acts along). Rendering uses a private ``Figure`` + Agg canvas, never
pyplot's global state, so it is safe in threads.
"""
from __future__ import annotations

import io
import os
from itertools import combinations
from pathlib import Path
from typing import Any, Iterable

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.ticker import FixedLocator, MaxNLocator

from solver.errors import SolverError
from solver.results import MAX_PREVIEW_POINTS, RESULT_FILE, list_frames, read_frame, read_scene
from solver.units import unit_of_field, with_unit

PREVIEW_FILE = "preview.png"
DEFAULT_FIELD = "velocity_magnitude"
DPI = 100
# Squares drawn a little larger than the particle spacing so a body has no seams.
MARKER_OVERLAP = 1.1
# The most ticks a 3D axis gets, then fewer until their labels are clear of each other
# (matplotlib's default locator counts ticks for a flat axis of that width: a foreshortened
# depth axis got ten labels on top of each other).
TICKS_3D = (6, 5, 4, 3, 2)
TICK_LABEL_GAP = 8.0   # pixels (half an em): labels closer than this read as one ("1.0 0.0")


def von_mises(voigt: np.ndarray) -> np.ndarray:
    """Von Mises value of Voigt tensors (columns xx yy zz yz xz xy)."""
    xx, yy, zz, yz, xz, xy = voigt.T
    return np.sqrt(
        0.5 * ((xx - yy) ** 2 + (yy - zz) ** 2 + (zz - xx) ** 2) + 3.0 * (yz**2 + xz**2 + xy**2)
    )


# Fields computed from others when the frame does not store them: name -> (source, function).
DERIVED = {
    "velocity_magnitude": ("velocity", lambda v: np.linalg.norm(v, axis=1)),
    "von_mises": ("stress", von_mises),
    "pressure": ("stress", lambda s: -(s[:, 0] + s[:, 1] + s[:, 2]) / 3.0),
}


def available_fields(datasets: Iterable[str]) -> list[str]:
    """The names a preview of a frame with these datasets can be coloured by."""
    datasets = set(datasets)
    derived = {name for name, (source, _) in DERIVED.items() if source in datasets}
    return sorted(datasets | derived)


class UnknownField(SolverError, ValueError):
    """A field a frame does not have and cannot derive; ``available``: those it can draw."""

    def __init__(self, field: str, available: list[str]):
        self.field, self.available = field, available
        super().__init__(f"field {field!r} is not in this frame; available: {', '.join(available)}")


def scalar_values(fields: dict[str, np.ndarray], name: str) -> tuple[np.ndarray, str]:
    """One value per particle for ``name`` and the label saying how it was reduced."""
    if name not in fields and name in DERIVED and DERIVED[name][0] in fields:
        source, function = DERIVED[name]
        return function(np.asarray(fields[source], dtype=float)), name
    if name not in fields:
        raise UnknownField(name, available_fields(fields))
    data = np.asarray(fields[name], dtype=float).reshape(len(fields[name]), -1)
    if data.shape[1] == 1:
        return data[:, 0], name
    if data.shape[1] == 6:
        return von_mises(data), f"{name} (von Mises)"
    return np.linalg.norm(data, axis=1), f"|{name}|"


def default_field(fields: dict[str, np.ndarray], scene: dict[str, Any]) -> str:
    """The scene's ``output.preview.field`` when the frame has it, else velocity magnitude."""
    preview = (scene.get("output") or {}).get("preview") or {}
    available = available_fields(fields)
    for name in (preview.get("field"), DEFAULT_FIELD):
        if name in available:
            return name
    return "body"  # always written: a frame without velocity is still drawn


def axis_labels(scene: dict[str, Any]) -> list[str]:
    """The names of the scene's axes with their unit: r and z for an axisymmetric scene."""
    names = ["r", "z"] if scene.get("axisymmetric") else ["x", "y", "z"][: int(scene["dimension"])]
    return [with_unit(name, unit_of_field(scene.get("units"), "length")) for name in names]


def frame_values(scene: dict[str, Any], snapshot: dict[str, Any], field: str | None) -> tuple[np.ndarray, np.ndarray, str]:
    """Positions (n, dimension), one value per particle and the colour label (with its unit)
    of a frame read by solver.results.read_frame."""
    fields = snapshot["fields"]
    name = field or default_field(fields, scene)
    values, label = scalar_values(fields, name)
    dimension = int(scene["dimension"])
    position = np.asarray(fields["position"], dtype=float).reshape(len(values), dimension)
    return position, values, with_unit(label, unit_of_field(scene.get("units"), name))


def new_figure(dimension: int) -> Figure:
    figure = Figure(figsize=(7.0, 6.0) if dimension > 1 else (8.0, 4.5), dpi=DPI)
    FigureCanvasAgg(figure)
    return figure


def draw_frame(figure: Figure, scene: dict[str, Any], snapshot: dict[str, Any], field: str | None,
               value_range: tuple[float, float] | None = None) -> None:
    """Draw a frame into an empty figure; `value_range`: the colour scale (default: the frame's
    own), fixed by an animation so that colours mean the same in every frame."""
    position, values, label = frame_values(scene, snapshot, field)
    low, high = value_range or colour_range(values)
    dimension = int(scene["dimension"])
    axes = axis_labels(scene)
    lower, upper = _extent(scene, position)
    spacing = _particle_spacing(scene, snapshot["fields"]["body"], lower, upper, len(values))
    spacing = spacing * snapshot.get("every", 1) ** (1.0 / dimension)   # every k-th particle: k^(1/d) apart
    if dimension == 1:
        _plot_1d(figure, position[:, 0], values, label, lower, upper, axes, (low, high))
    elif dimension == 2:
        _plot_2d(figure, position, values, label, lower, upper, spacing, axes, (low, high))
    else:
        _plot_3d(figure, position, values, label, lower, upper, spacing, axes, (low, high))
    time_unit = unit_of_field(scene.get("units"), "time")
    figure.suptitle(
        f"{scene.get('name') or 'scene'}\n"
        f"t = {snapshot['time']:.6g}{' ' + time_unit if time_unit else ''}   step {snapshot['step']}   "
        f"frame {snapshot['index']}",
        fontsize=11,
    )


def render_preview(
    result_path: str | os.PathLike,
    frame: int = -1,
    field: str | None = None,
    out: str | os.PathLike | None = None,
) -> bytes:
    """Render a frame (``-1``: the last) of a result file as PNG bytes, also written to ``out``.

    Raises :class:`UnknownField` (a ``ValueError``) naming the field and the available
    ones for an unknown ``field``, and :class:`solver.results.FrameNotFound` (an
    ``IndexError``) for a frame out of range.
    """
    scene = read_scene(result_path)
    figure = new_figure(int(scene["dimension"]))
    draw_frame(figure, scene, read_frame(result_path, frame, MAX_PREVIEW_POINTS), field)
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=DPI)
    png = buffer.getvalue()
    if out is not None:
        Path(out).write_bytes(png)
    return png


def finish_outputs(out_dir: str | os.PathLike, scene: Any) -> Path | None:
    """Write ``out_dir/preview.png`` of the last frame; the run loop calls it after closing the writer.

    ``scene`` is the validated scene; its ``output.preview.field`` is drawn
    when the last frame has it, velocity magnitude otherwise. Returns the PNG
    path, or None when the result has no frame to draw (a run that failed
    before its first frame).
    """
    result = Path(out_dir) / RESULT_FILE
    frames = list_frames(result)
    if not frames:
        return None
    wanted = scene.output.preview.field
    png = Path(out_dir) / PREVIEW_FILE
    field = wanted if wanted in available_fields(frames[-1]["fields"]) else None
    render_preview(result, field=field, out=png)
    return png


# -- geometry of the plot ----------------------------------------------------


def _extent(scene: dict[str, Any], position: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The grid box, or (no grid box: tlmpm may leave it out) the particles' bounding box with a
    margin; in tlmpm the grid box is the reference configuration, which the particles may leave
    (a machined chip): then the box is widened to them."""
    grid = scene.get("grid")
    finite = position[np.all(np.isfinite(position), axis=1)]
    has_box = bool(grid) and grid.get("lower") is not None and grid.get("upper") is not None
    if has_box:
        lower, upper = np.asarray(grid["lower"], dtype=float), np.asarray(grid["upper"], dtype=float)
        if len(finite) == 0 or (np.all(finite >= lower) and np.all(finite <= upper)):
            return lower, upper
        return np.minimum(lower, finite.min(axis=0)), np.maximum(upper, finite.max(axis=0))
    if len(finite) == 0:
        return np.zeros(position.shape[1]), np.ones(position.shape[1])
    lower, upper = finite.min(axis=0), finite.max(axis=0)
    margin = 0.05 * max(float(np.max(upper - lower)), 1e-12)
    return lower - margin, upper + margin


def _particle_spacing(
    scene: dict[str, Any], body: np.ndarray, lower: np.ndarray, upper: np.ndarray, count: int
) -> np.ndarray:
    """Initial distance between neighbouring particles, per particle (cell size / particles per cell)."""
    grid = scene.get("grid")
    if not grid or count == 0:
        volume = float(np.prod(upper - lower))
        return np.full(count, (volume / max(count, 1)) ** (1.0 / len(lower)))
    cell = float(np.max(grid["cell_size"]))   # cells of unequal sides: no gaps between the rows
    per_body = np.array(
        [cell / float(np.max(b.get("particles_per_cell") or 1)) for b in scene.get("bodies", [])]
        or [cell]
    )
    return per_body[np.clip(np.asarray(body, dtype=int), 0, len(per_body) - 1)]


def colour_range(values: np.ndarray) -> tuple[float, float]:
    finite = values[np.isfinite(values)]
    if len(finite) == 0:
        return 0.0, 1.0
    low, high = float(finite.min()), float(finite.max())
    if high - low <= 1e-12 * max(abs(low), abs(high), 1e-300):
        pad = 0.5 * abs(low) if low else 0.5
        return low - pad, high + pad
    return low, high


def _colour_bar(figure: Figure, mappable, axes, label: str, low: float, high: float) -> None:
    bar = figure.colorbar(mappable, ax=axes, shrink=0.85, pad=0.04)
    bar.set_label(f"{label}\nrange [{low:.4g}, {high:.4g}]")


def _plot_1d(figure: Figure, x: np.ndarray, values: np.ndarray, label: str, lower, upper,
             names: list[str], value_range: tuple[float, float]) -> None:
    axes = figure.add_subplot()
    order = np.argsort(x)
    axes.plot(x[order], values[order], "-", color="0.6", linewidth=1.0, zorder=1)
    axes.scatter(x[order], values[order], s=18, color="tab:blue", zorder=2)
    axes.set_xlim(lower[0], upper[0])
    low, high = value_range
    axes.set_ylim(low - 0.08 * (high - low), high + 0.08 * (high - low))
    axes.set_xlabel(names[0])
    axes.set_ylabel(f"{label}\nrange [{low:.4g}, {high:.4g}]")
    axes.grid(True, alpha=0.3)
    figure.subplots_adjust(top=0.84, left=0.14)


def _plot_2d(figure: Figure, position, values, label: str, lower, upper, spacing,
             names: list[str], value_range: tuple[float, float]) -> None:
    axes = figure.add_subplot()
    low, high = value_range
    points = axes.scatter(
        position[:, 0], position[:, 1], c=values, vmin=low, vmax=high,
        cmap="viridis", marker="s", linewidths=0,
    )
    axes.set_xlim(lower[0], upper[0])
    axes.set_ylim(lower[1], upper[1])
    axes.set_aspect("equal")
    axes.set_xlabel(names[0])
    axes.set_ylabel(names[1])
    axes.set_facecolor("0.96")
    _colour_bar(figure, points, axes, label, low, high)
    figure.subplots_adjust(top=0.86)
    # Marker sizes are in points: measure the laid-out axes to convert spacing to points.
    figure.canvas.draw()
    points_per_unit = axes.get_window_extent().width / (upper[0] - lower[0]) * 72.0 / DPI
    points.set_sizes((MARKER_OVERLAP * spacing * points_per_unit) ** 2)


def _plot_3d(figure: Figure, position, values, label: str, lower, upper, spacing,
             names: list[str], value_range: tuple[float, float]) -> None:
    axes = figure.add_subplot(projection="3d")
    low, high = value_range
    # Matplotlib draws its z axis upwards; the scene's y is the vertical one.
    points = axes.scatter(
        position[:, 0], position[:, 2], position[:, 1], c=values, vmin=low, vmax=high,
        cmap="viridis", marker="o", linewidths=0, depthshade=True,
    )
    axes.set_xlim(lower[0], upper[0])
    axes.set_ylim(lower[2], upper[2])
    axes.set_zlim(lower[1], upper[1])
    axes.set_box_aspect((upper[0] - lower[0], upper[2] - lower[2], upper[1] - lower[1]))
    axes.set_xlabel(names[0])
    axes.set_ylabel(names[2])
    axes.set_zlabel(names[1])
    axes.view_init(elev=22, azim=-60)
    _colour_bar(figure, points, axes, label, low, high)
    figure.subplots_adjust(top=0.88)
    _clear_tick_labels(figure, axes, points)
    figure.canvas.draw()
    # The projected box is about 0.55 of the axes width along its longest edge.
    longest = float(np.max(upper - lower))
    points_per_unit = 0.55 * axes.get_window_extent().width / longest * 72.0 / DPI
    points.set_sizes((1.3 * spacing * points_per_unit) ** 2)


def tick_label_boxes(axis, renderer) -> list[tuple[float, Any]]:
    """The drawn tick labels of an axis: (tick value, its label's box in pixels); after a draw."""
    low, high = sorted(axis.get_view_interval())
    slack = 1e-9 * (high - low)
    locations = axis.get_majorticklocs()
    return [(float(location), tick.label1.get_window_extent(renderer))
            for location, tick in zip(locations, axis.get_major_ticks(len(locations)))
            if low - slack <= location <= high + slack and tick.label1.get_visible() and tick.label1.get_text()]


def _clear_tick_labels(figure: Figure, axes, points) -> None:
    """Tick labels of a 3D plot clear of each other: each axis with as many ticks (TICKS_3D) as
    its labels have room for, then where two axes meet at a corner (an x label on a depth
    label), the label of the later axis left out. Drawn without the particles (the costly part)."""
    points.set_visible(False)
    renderer = figure.canvas.get_renderer()
    axes_3d = (axes.xaxis, axes.zaxis, axes.yaxis)   # x, the vertical axis, then depth: kept in this order
    for axis in axes_3d:
        for count in TICKS_3D:
            axis.set_major_locator(MaxNLocator(nbins=count - 1))
            figure.canvas.draw()
            boxes = [box.padded(TICK_LABEL_GAP / 2) for _, box in tick_label_boxes(axis, renderer)]
            if not any(a.overlaps(b) for a, b in combinations(boxes, 2)):
                break
    kept = []
    for axis in axes_3d:
        labels = [(value, box.padded(TICK_LABEL_GAP / 2)) for value, box in tick_label_boxes(axis, renderer)]
        clear = [(value, box) for value, box in labels if not any(box.overlaps(other) for other in kept)]
        if len(clear) < len(labels):
            axis.set_major_locator(FixedLocator([value for value, _ in clear]))
        kept += [box for _, box in clear]
    points.set_visible(True)
