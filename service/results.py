"""Reading a job's result for the API: preview images (cached per frame and field)
and the time series as JSON. A running job's file is read as it is being written
(the solver flushes complete frames); nothing of it is cached."""
from __future__ import annotations

import math
import os
import tempfile
import threading
from pathlib import Path

from solver.preview import UnknownField, render_preview
from solver.results import FrameNotFound, read_series

from core.paths import JobFiles
from service.errors import ApiError, validation_error

# Rendering is CPU-bound and memory-hungry: one at a time per API process.
_render_lock = threading.Lock()


def _unreadable(files: JobFiles, exc: Exception) -> ApiError:
    message = str(exc).replace(str(files.dir), "<job>")  # not the server's paths
    return ApiError(409, "result_not_ready", f"the result cannot be read yet: {message}")


def preview(files: JobFiles, frame: int, field: str | None, cache: bool) -> Path | bytes:
    """The PNG of `frame` coloured by `field` (None: the scene's preview field)."""
    cached = files.preview(frame, field or "default")
    if cache and cached.is_file():
        return cached
    with _render_lock:
        if cache and cached.is_file():  # rendered while we waited
            return cached
        try:
            png = render_preview(files.result, frame=frame, field=field)
        except FrameNotFound as exc:  # named as "the result": not the server's path
            raise validation_error([{"path": "frame", "message": exc.describe("the result")}]) from None
        except UnknownField as exc:
            if field is not None and exc.field == field:
                raise validation_error([{"path": "field", "message": str(exc)}]) from None
            raise _unreadable(files, exc) from None
        except (OSError, KeyError, ValueError, IndexError) as exc:
            raise _unreadable(files, exc) from None
        if not cache:
            return png
        cached.parent.mkdir(exist_ok=True)
        handle, temp = tempfile.mkstemp(dir=cached.parent, suffix=".part")
        with os.fdopen(handle, "wb") as out:
            out.write(png)
        os.chmod(temp, 0o644)
        os.replace(temp, cached)  # readers never see half a file
        return cached


def series(files: JobFiles) -> dict[str, list[float | None]]:
    """`{name: [values]}`; non-finite values (a blown-up run) become null."""
    try:
        data = read_series(files.result)
    except (OSError, KeyError, ValueError) as exc:
        raise _unreadable(files, exc) from None
    return {name: [v if math.isfinite(v) else None for v in values.tolist()]
            for name, values in data.items()}
