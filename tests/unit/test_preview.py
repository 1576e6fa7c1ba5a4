"""Preview PNGs of result frames."""
import io
import struct
import threading

import numpy as np
import pytest
from matplotlib.image import imread

from solver.preview import available_fields, finish_outputs, render_preview, scalar_values, von_mises
from solver.results import ResultWriter
from solver.scene_checks import load_scene

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def scene(dimension: int, preview_field: str = "velocity_magnitude"):
    return load_scene({
        "version": 1, "name": f"preview {dimension}d", "dimension": dimension,
        "grid": {"lower": [0.0] * dimension, "upper": [1.0] * dimension, "cell_size": 0.1},
        "materials": {"m": {"model": "linear_elastic", "density": 1, "youngs_modulus": 1, "poisson_ratio": 0.0}},
        "bodies": [{"name": "block", "material": "m",
                    "geometry": {"type": "box", "lower": [0.2] * dimension, "upper": [0.6] * dimension}}],
        "time": {"end": 1.0, "dt": 0.01},
        "output": {"frames": 2, "preview": {"field": preview_field}},
    })


def block(dimension: int) -> np.ndarray:
    """Particles of the scene's block: 2 per cell and axis."""
    axis = np.arange(0.225, 0.6, 0.05)
    grids = np.meshgrid(*[axis] * dimension, indexing="ij")
    return np.stack([g.ravel() for g in grids], axis=1)


def write(tmp_path, dimension: int, frames: int = 2, **scene_options):
    position = block(dimension)
    n = len(position)
    with ResultWriter(tmp_path, scene(dimension, **scene_options), "0") as writer:
        for k in range(frames):
            writer.write_frame(k * 10, k * 0.1, {
                "id": np.arange(n), "body": np.zeros(n), "mass": np.ones(n),
                "position": position + 0.01 * k, "velocity": np.tile(np.arange(1, dimension + 1), (n, 1)) * k,
                "stress": np.outer(position[:, 0], [1, 0, 0, 0, 0, 0]),
            })
    return tmp_path / "result.h5"


def png_size(png: bytes) -> tuple[int, int]:
    assert png[:8] == PNG_MAGIC
    assert png[12:16] == b"IHDR"
    return struct.unpack(">II", png[16:24])


def coloured_pixels(png: bytes) -> int:
    """Pixels of clearly saturated colour (markers, colour map), not black/grey/white."""
    rgb = imread(io.BytesIO(png), format="png")[..., :3]
    return int(((rgb.max(axis=2) - rgb.min(axis=2)) > 0.2).sum())


# 1D draws blue markers and no colour bar; in 2D and 3D the colour bar alone covers
# about 3% of the 700 x 600 image, the particles of the block several % more.
@pytest.mark.parametrize("dimension, least_coloured", [(1, 200), (2, 0.06 * 700 * 600), (3, 0.045 * 700 * 600)])
def test_renders_a_png_for_each_dimension(tmp_path, dimension, least_coloured):
    png = render_preview(write(tmp_path, dimension))
    width, height = png_size(png)
    assert (width, height) == ((800, 450) if dimension == 1 else (700, 600))
    assert coloured_pixels(png) > least_coloured


def test_out_receives_the_same_bytes(tmp_path):
    path = write(tmp_path, 2)
    png = render_preview(path, frame=0, field="stress", out=tmp_path / "s.png")
    assert (tmp_path / "s.png").read_bytes() == png


def test_fields_change_the_picture(tmp_path):
    path = write(tmp_path, 2)
    assert render_preview(path, field="stress") != render_preview(path, field="mass")
    assert render_preview(path, frame=0) != render_preview(path, frame=1)


def test_unknown_field_names_it_and_the_available_ones(tmp_path):
    path = write(tmp_path, 2)
    with pytest.raises(ValueError) as error:
        render_preview(path, field="temperature")
    message = str(error.value)
    assert "'temperature'" in message
    for name in ("velocity", "stress", "velocity_magnitude", "von_mises", "pressure", "mass"):
        assert name in message


def test_frame_out_of_range_is_an_index_error(tmp_path):
    with pytest.raises(IndexError, match="2 frames"):
        render_preview(write(tmp_path, 2), frame=5)


def test_reductions_to_one_value_per_particle():
    fields = {
        "velocity": np.array([[3.0, 4.0], [0.0, 1.0]]),
        # uniaxial stress s: von Mises s; pure shear t: sqrt(3) t; pressure -tr/3
        "stress": np.array([[2.0, 0, 0, 0, 0, 0], [0, 0, 0, 0, 0, 1.0]]),
        "mass": np.array([1.0, 2.0]),
    }
    np.testing.assert_allclose(scalar_values(fields, "velocity_magnitude")[0], [5.0, 1.0])
    np.testing.assert_allclose(scalar_values(fields, "velocity")[0], [5.0, 1.0])
    np.testing.assert_allclose(scalar_values(fields, "von_mises")[0], [2.0, np.sqrt(3.0)])
    np.testing.assert_allclose(scalar_values(fields, "stress")[0], [2.0, np.sqrt(3.0)])
    assert scalar_values(fields, "stress")[1] == "stress (von Mises)"
    np.testing.assert_allclose(scalar_values(fields, "pressure")[0], [-2.0 / 3.0, 0.0])
    np.testing.assert_allclose(scalar_values(fields, "mass")[0], [1.0, 2.0])
    assert available_fields(fields) == ["mass", "pressure", "stress", "velocity", "velocity_magnitude", "von_mises"]


def test_von_mises_matches_the_solver_fields():
    from solver.fields import VOIGT, von_mises as tensor_von_mises

    rng = np.random.default_rng(1)
    tensors = rng.normal(size=(20, 3, 3))
    tensors = tensors + tensors.transpose(0, 2, 1)
    voigt = np.stack([tensors[:, a, b] for a, b in VOIGT], axis=1)
    np.testing.assert_allclose(von_mises(voigt), tensor_von_mises(tensors))


def test_default_field_is_the_scenes_preview_field(tmp_path):
    by_scene = render_preview(write(tmp_path / "a", 2, preview_field="von_mises"))
    explicit = render_preview(tmp_path / "a" / "result.h5", field="von_mises")
    assert by_scene == explicit


def test_renders_concurrently_from_threads(tmp_path):
    path = write(tmp_path, 2)
    results = []

    def render(field):
        results.append(render_preview(path, field=field))

    threads = [threading.Thread(target=render, args=(f,)) for f in ("mass", "stress", "velocity", "von_mises")]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert len(results) == 4 and all(png[:8] == PNG_MAGIC for png in results)


def test_finish_outputs_writes_preview_png(tmp_path):
    write(tmp_path, 2)
    png = finish_outputs(tmp_path, scene(2))
    assert png == tmp_path / "preview.png" and png.read_bytes()[:8] == PNG_MAGIC


def test_finish_outputs_without_frames_writes_nothing(tmp_path):
    write(tmp_path, 2, frames=0)
    assert finish_outputs(tmp_path, scene(2)) is None
    assert not (tmp_path / "preview.png").exists()


def test_finish_outputs_falls_back_when_the_preview_field_is_not_written(tmp_path):
    path = write(tmp_path, 2, preview_field="density")  # a valid field, but not in these frames
    png = finish_outputs(tmp_path, scene(2, preview_field="density"))
    assert png.read_bytes() == render_preview(path, field="velocity_magnitude")


@pytest.mark.parametrize("upper", [[0.14, 0.14, 0.08], [0.00912, 0.0258, 0.00912], [1.0, 1.0, 1.0]],
                         ids=["bracket", "taylor-bar", "unit-cube"])
def test_3d_tick_labels_are_clear_of_each_other(upper):
    """The boxes of the 3D examples: matplotlib's own ticks put the x label 0.14 on the depth
    label 0.00 at their corner, and ten depth labels on top of each other along a short axis;
    the unit cube's x label 1.0 ran up against the depth label 0.0."""
    from itertools import combinations

    from solver.preview import draw_frame, new_figure, tick_label_boxes

    document = scene(3).model_dump(mode="json")
    document["grid"].update(lower=[0.0] * 3, upper=upper, cell_size=min(upper) / 10)
    position = np.asarray(upper) * (0.2 + 0.6 * np.random.default_rng(1).random((500, 3)))
    figure = new_figure(3)
    draw_frame(figure, document, {"fields": {"position": position, "body": np.zeros(500), "velocity": position},
                                  "time": 0.0, "step": 0, "index": 0}, "velocity")
    figure.canvas.draw()
    renderer = figure.canvas.get_renderer()
    axes = figure.axes[0]
    labels = {axis: tick_label_boxes(axis, renderer) for axis in (axes.xaxis, axes.yaxis, axes.zaxis)}
    assert all(len(found) >= 2 for found in labels.values()), "each axis keeps two labels at least"
    boxes = [(axis.axis_name, value, extent) for axis, found in labels.items() for value, extent in found]
    # at least a pixel apart (a gap of 1 px each side of a box)
    assert not [(a[:2], b[:2]) for a, b in combinations(boxes, 2) if a[2].padded(1).overlaps(b[2].padded(1))]
