"""Animations of a result (solver/animation.py, `mpm animate`), and the axis and unit labels
that previews, animations and the viewer share (solver/preview.py, solver/units.py)."""
import numpy as np
import imageio_ffmpeg
import pytest
from matplotlib import colormaps
from PIL import Image

from solver import cli
from solver.animation import AnimationError, render_animation
from solver.preview import axis_labels, draw_frame, new_figure
from solver.results import ResultWriter, read_frame, read_scene
from solver.scene_checks import load_scene
from test_preview import block, scene as preview_scene

FRAMES = 3


def write_uniform(tmp_path, frames=FRAMES):
    """A 2D block whose particles all move at speed k in frame k: one colour per frame."""
    position = block(2)
    n = len(position)
    with ResultWriter(tmp_path, preview_scene(2), "0") as writer:
        for k in range(frames):
            writer.write_frame(k * 10, k * 0.1, {
                "id": np.arange(n), "body": np.zeros(n), "mass": np.ones(n), "position": position,
                "velocity": np.tile([float(k), 0.0], (n, 1)), "stress": np.zeros((n, 6))})
    return tmp_path / "result.h5"


def particle_colour(image: Image.Image) -> np.ndarray:
    """The most frequent saturated colour: the block's (the colour bar spreads over many)."""
    rgb = np.asarray(image.convert("RGB")).reshape(-1, 3).astype(int)
    saturated = rgb[(rgb.max(axis=1) - rgb.min(axis=1)) > 40]
    colours, counts = np.unique(saturated, axis=0, return_counts=True)
    return colours[np.argmax(counts)]


def test_a_gif_has_every_frame_on_one_colour_scale(tmp_path):
    out = render_animation(write_uniform(tmp_path), tmp_path / "run.gif", fps=5)
    gif = Image.open(out)
    assert gif.n_frames == FRAMES and gif.info["duration"] == 200
    colours = []
    for k in range(FRAMES):
        gif.seek(k)
        colours.append(particle_colour(gif))
    # One scale over the run: speed 0 is the bottom of viridis, the top speed its top. A scale
    # per frame would draw every (uniform) frame in the same middle colour. GIF palettes
    # quantise the colours: within 40 of 255 per channel.
    lowest, highest = (np.array(colormaps["viridis"](v)[:3]) * 255 for v in (0.0, 1.0))
    assert np.abs(colours[0] - lowest).max() < 40
    assert np.abs(colours[-1] - highest).max() < 40


def test_an_mp4_is_h264_with_every_frame(tmp_path):
    out = render_animation(write_uniform(tmp_path), tmp_path / "run.mp4", field="velocity")
    assert out.read_bytes()[4:8] == b"ftyp"
    frames, _ = imageio_ffmpeg.count_frames_and_secs(str(out))
    assert frames == FRAMES


def test_another_format_or_an_empty_result_is_refused(tmp_path):
    result = write_uniform(tmp_path)
    with pytest.raises(AnimationError, match="a .gif or an .mp4"):
        render_animation(result, tmp_path / "run.avi")
    empty = tmp_path / "empty"
    with ResultWriter(empty, preview_scene(2), "0"):
        pass
    with pytest.raises(AnimationError, match="no frame"):
        render_animation(empty / "result.h5", tmp_path / "run.gif")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["empty", "result.h5", "result.xdmf"]  # no leftovers


def test_mpm_animate_writes_the_file_and_names_errors(tmp_path, capsys):
    result = write_uniform(tmp_path)
    assert cli.main(["animate", str(result), "-o", str(tmp_path / "a.gif"), "--fps", "20"]) == 0
    assert capsys.readouterr().out.strip() == str(tmp_path / "a.gif")
    assert Image.open(tmp_path / "a.gif").n_frames == FRAMES
    assert cli.main(["animate", str(result), "--field", "nope", "-o", str(tmp_path / "b.gif")]) == 1
    assert "field 'nope' is not in this frame" in capsys.readouterr().err


def labelled_scene(axisymmetric: bool):
    return load_scene({
        "dimension": 2, "axisymmetric": axisymmetric,
        "grid": {"lower": [0, 0], "upper": [10, 10], "cell_size": 1},
        "materials": {"m": {"model": "linear_elastic", "density": 7.8e-9, "youngs_modulus": 2e5,
                            "poisson_ratio": 0.3}},
        "bodies": [{"name": "b", "material": "m", "geometry": {"type": "box", "lower": [0, 2], "upper": [4, 6]}}],
        "time": {"end": 1.0},
        "units": {"length": "mm", "time": "ms", "mass": "t", "stress": "MPa"},
    })


@pytest.mark.parametrize("axisymmetric, names", [(True, ["r [mm]", "z [mm]"]), (False, ["x [mm]", "y [mm]"])])
def test_axes_are_r_and_z_for_axisymmetric_scenes_with_the_units(tmp_path, axisymmetric, names):
    scene = labelled_scene(axisymmetric)
    position = block(2) * 10
    n = len(position)
    with ResultWriter(tmp_path, scene, "0") as writer:
        writer.write_frame(0, 0.0, {"id": np.arange(n), "body": np.zeros(n), "mass": np.ones(n),
                                    "position": position, "velocity": np.zeros((n, 2)), "stress": np.zeros((n, 6))})
    stored = read_scene(tmp_path / "result.h5")
    assert axis_labels(stored) == names
    figure = new_figure(2)
    draw_frame(figure, stored, read_frame(tmp_path / "result.h5"), "von_mises")
    plot, bar = figure.axes
    assert [plot.get_xlabel(), plot.get_ylabel()] == names
    assert bar.get_ylabel().startswith("von_mises [MPa]")
    assert "t = 0 ms" in figure.texts[0].get_text()


def test_derived_units_and_unlabelled_scenes():
    from solver.units import unit_of_field
    units = {"length": "m", "time": "s", "mass": "kg"}
    assert unit_of_field(units, "velocity_magnitude") == "m/s"
    assert unit_of_field(units, "stress") == "kg/(m·s²)"  # no stress label given: built from the base units
    assert unit_of_field(units, "density") == "kg/m³"
    assert unit_of_field(units, "plastic_strain") is None
    assert unit_of_field(None, "stress") is None
