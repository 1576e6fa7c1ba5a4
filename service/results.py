"""Reading a job's result for the API: preview images (cached per frame and field),
animations (cached per field and format), the frames and their particles for the
dashboard's viewer, and the time series as JSON. A running job's file is read as it
is being written (the solver flushes complete frames); nothing of it is cached."""
from __future__ import annotations

import json
import math
import os
import struct
import tempfile
import threading
from contextlib import contextmanager
from pathlib import Path
from typing import Any, Callable, Iterator

import numpy as np

from solver.animation import AnimationError, render_animation
from solver.preview import UnknownField, available_fields, axis_labels, colour_range, default_field, frame_values, \
    render_preview
from solver.results import FrameNotFound, list_frames, read_frame, read_scene, read_series
from solver.units import unit_of_field

from core.paths import JobFiles
from service.errors import ApiError, validation_error

# Rendering is CPU-bound and memory-hungry: one at a time per API process.
_render_lock = threading.Lock()


def _unreadable(files: JobFiles, exc: Exception) -> ApiError:
    message = str(exc).replace(str(files.dir), "<job>")  # not the server's paths
    return ApiError(409, "result_not_ready", f"the result cannot be read yet: {message}")


@contextmanager
def _reading(files: JobFiles, field: str | None) -> Iterator[None]:
    """Errors of reading a result as API errors: 422 naming `frame` or `field`, 409 otherwise."""
    try:
        yield
    except FrameNotFound as exc:  # named as "the result": not the server's path
        raise validation_error([{"path": "frame", "message": exc.describe("the result")}]) from None
    except UnknownField as exc:
        if field is not None and exc.field == field:
            raise validation_error([{"path": "field", "message": str(exc)}]) from None
        raise _unreadable(files, exc) from None
    except (OSError, KeyError, ValueError, IndexError) as exc:
        raise _unreadable(files, exc) from None


def _cached(cached: Path, cache: bool, render: Callable[[Path], None]) -> Path | bytes:
    """The cached file, else rendered (one rendering at a time) into it, or into memory when
    not `cache` (a running job's frames change)."""
    if cache and cached.is_file():
        return cached
    with _render_lock:
        if cache and cached.is_file():  # rendered while we waited
            return cached
        cached.parent.mkdir(exist_ok=True)
        handle, temp = tempfile.mkstemp(dir=cached.parent, prefix=".part-", suffix=cached.suffix)
        os.close(handle)
        try:
            render(Path(temp))
            if not cache:
                return Path(temp).read_bytes()
            os.chmod(temp, 0o644)
            os.replace(temp, cached)  # readers never see half a file
        finally:
            if os.path.exists(temp):
                os.unlink(temp)
        return cached


def preview(files: JobFiles, frame: int, field: str | None, cache: bool) -> Path | bytes:
    """The PNG of `frame` coloured by `field` (None: the scene's preview field)."""
    with _reading(files, field):
        return _cached(files.preview(frame, field or "default"), cache,
                       lambda out: render_preview(files.result, frame=frame, field=field, out=out))


def animation(files: JobFiles, field: str | None, suffix: str) -> Path:
    """Every frame as an animation (.gif or .mp4), cached: only finished jobs have one."""
    with _reading(files, field):
        try:
            return _cached(files.animation(field or "default", suffix), True,
                           lambda out: render_animation(files.result, out, field=field))
        except AnimationError as exc:
            raise ApiError(409, "result_not_ready", str(exc)) from None


def frames(files: JobFiles) -> dict[str, Any]:
    """What the viewer needs to know before it asks for particles: the frames written so far
    (index, time, step, particles), the fields it can colour by, the axes and the units."""
    with _reading(files, None):
        scene, listed = read_scene(files.result), list_frames(files.result)
    fields = listed[-1]["fields"] if listed else []
    units = scene.get("units")
    return {"frames": [{key: frame[key] for key in ("index", "time", "step", "particles")} for frame in listed],
            "fields": available_fields(fields),
            "preview_field": default_field(dict.fromkeys(fields), scene) if listed else None,
            "dimension": int(scene["dimension"]), "axisymmetric": bool(scene.get("axisymmetric")),
            "axes": axis_labels(scene), "units": units, "time_unit": unit_of_field(units, "time")}


def particles(files: JobFiles, frame: int, field: str | None) -> bytes:
    """One frame's particles for the viewer, packed (docs/service.md, "The viewer's particles"):
    a little-endian uint32 n, n bytes of JSON header (padded with spaces to a multiple of 4),
    then float32 positions (count x 3, zeros for the missing axes) and float32 values (count)."""
    with _reading(files, field):
        scene = read_scene(files.result)
        snapshot = read_frame(files.result, frame)
        position, values, label = frame_values(scene, snapshot, field)
    xyz = np.zeros((len(values), 3), dtype="<f4")
    xyz[:, : position.shape[1]] = position
    header = json.dumps({"index": snapshot["index"], "time": snapshot["time"], "step": snapshot["step"],
                         "count": len(values), "field": field or default_field(snapshot["fields"], scene),
                         "label": label, "range": list(colour_range(values))}).encode()
    header += b" " * (-len(header) % 4)
    return struct.pack("<I", len(header)) + header + xyz.tobytes() + np.asarray(values, dtype="<f4").tobytes()


def series(files: JobFiles) -> dict[str, list[float | None]]:
    """`{name: [values]}`; non-finite values (a blown-up run) become null."""
    try:
        data = read_series(files.result)
    except (OSError, KeyError, ValueError) as exc:
        raise _unreadable(files, exc) from None
    return {name: [v if math.isfinite(v) else None for v in values.tolist()]
            for name, values in data.items()}
