"""Animations of a result file: its frames drawn as the previews are (solver/preview.py),
with one colour scale for the whole run, encoded as GIF (Pillow, which matplotlib
already needs) or MP4 (H.264 by the ffmpeg binary that the imageio-ffmpeg wheel
ships, so no system ffmpeg is needed). `mpm animate`, the API's
`/v1/jobs/{id}/animation.gif|mp4` and the SDK's `job.animate()` all come here."""
from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Callable, Iterator

import numpy as np

from solver.errors import SolverError
from solver.preview import colour_range, draw_frame, frame_values, new_figure
from solver.results import list_frames, read_frame, read_scene

DEFAULT_FPS = 10


class AnimationError(SolverError, ValueError):
    """An animation that cannot be made (a format not known, a result without frames)."""


def _frames(result: Path, field: str | None) -> tuple[dict, list[int], tuple[float, float]]:
    """The scene, the frame indices and one colour range over all of them."""
    scene = read_scene(result)
    indices = list(range(len(list_frames(result))))
    if not indices:
        raise AnimationError("the result has no frame to animate")
    lows, highs = [], []
    for index in indices:
        _, values, _ = frame_values(scene, read_frame(result, index), field)
        finite = values[np.isfinite(values)]
        if len(finite):
            lows.append(finite.min())
            highs.append(finite.max())
    value_range = colour_range(np.array(lows + highs)) if lows else (0.0, 1.0)
    return scene, indices, value_range


def _images(result: Path, field: str | None) -> Iterator[np.ndarray]:
    """Each frame as an RGB image (height, width, 3), all of one size."""
    scene, indices, value_range = _frames(result, field)
    for index in indices:
        figure = new_figure(int(scene["dimension"]))
        draw_frame(figure, scene, read_frame(result, index), field, value_range)
        figure.canvas.draw()
        yield np.asarray(figure.canvas.buffer_rgba())[:, :, :3].copy()


def _write_gif(images: Iterator[np.ndarray], path: Path, fps: float) -> None:
    from PIL import Image
    frames = [Image.fromarray(image).convert("P", palette=Image.Palette.ADAPTIVE, colors=255) for image in images]
    frames[0].save(path, format="GIF", save_all=True, append_images=frames[1:],
                   duration=max(20, round(1000 / fps)), loop=0, optimize=False)


def _write_mp4(images: Iterator[np.ndarray], path: Path, fps: float) -> None:
    import imageio_ffmpeg
    first = next(images)
    height, width = first.shape[:2]
    # yuv420p (what browsers and players decode) needs even sides; the figures are 700 x 600.
    writer = imageio_ffmpeg.write_frames(str(path), (width, height), fps=fps, codec="libx264",
                                         pix_fmt_in="rgb24", pix_fmt_out="yuv420p", macro_block_size=2,
                                         output_params=["-movflags", "+faststart"], ffmpeg_log_level="error")
    writer.send(None)
    try:
        writer.send(np.ascontiguousarray(first))
        for image in images:
            writer.send(np.ascontiguousarray(image))
    finally:
        writer.close()


WRITERS: dict[str, Callable[[Iterator[np.ndarray], Path, float], None]] = {".gif": _write_gif, ".mp4": _write_mp4}


def render_animation(result_path: str | os.PathLike, out: str | os.PathLike, field: str | None = None,
                     fps: float = DEFAULT_FPS) -> Path:
    """Write every frame of the result, coloured by `field` (default: the scene's preview
    field), to `out` (.gif or .mp4, chosen by its suffix); the file appears whole or not at all.

    Raises AnimationError for another suffix or a result without frames, and
    solver.preview.UnknownField for a field the frames do not have."""
    out = Path(out)
    writer = WRITERS.get(out.suffix.lower())
    if writer is None:
        raise AnimationError(f"cannot write {out.name!r}: an animation is a .gif or an .mp4 file")
    if not fps > 0:
        raise AnimationError(f"fps must be > 0, not {fps}")
    # The temporary file keeps the suffix: ffmpeg picks the container by it.
    handle, temp = tempfile.mkstemp(dir=out.parent, prefix=".part-", suffix=out.suffix)
    os.close(handle)
    try:
        writer(_images(Path(result_path), field), Path(temp), fps)
        os.chmod(temp, 0o644)
        os.replace(temp, out)
    finally:
        if os.path.exists(temp):
            os.unlink(temp)
    return out


__all__ = ["AnimationError", "DEFAULT_FPS", "render_animation"]
