"""result.h5 and result.xdmf against the layout of INTERFACES.md."""
import json
import math
import subprocess
import sys
import textwrap
import xml.etree.ElementTree as ET

import h5py
import numpy as np
import pytest

from solver.results import ResultWriter, list_frames, read_frame, read_scene, read_series
from solver.scene_checks import load_scene

N = 12  # particles per frame
TIMES = [0.0, 0.05, 0.1]
STEPS = [0, 50, 100]


def small_scene(dimension: int):
    """A valid scene of the given dimension (only its JSON and dimension matter here)."""
    lower, upper = [0.0] * dimension, [1.0] * dimension
    return load_scene({
        "version": 1, "name": f"test-{dimension}d", "dimension": dimension,
        "grid": {"lower": lower, "upper": upper, "cell_size": 0.25},
        "materials": {"m": {"model": "linear_elastic", "density": 1, "youngs_modulus": 1, "poisson_ratio": 0.0}},
        "bodies": [{"name": "b", "material": "m",
                    "geometry": {"type": "box", "lower": [0.25] * dimension, "upper": [0.75] * dimension}}],
        "time": {"end": 0.1, "dt": 0.001},
        "output": {"frames": 3, "fields": ["position", "velocity", "stress", "von_mises"]},
    })


def frame_fields(dimension: int, k: int) -> dict:
    rng = np.random.default_rng(k)
    return {
        "id": np.arange(N)[::-1],                  # any order, ints
        "body": np.zeros(N, dtype=np.int64),       # stored as int32
        "mass": np.full(N, 0.5),
        "position": rng.random((N, dimension)),
        "velocity": rng.random((N, dimension)),
        "stress": rng.random((N, 6)),
        "von_mises": rng.random(N),
        "deformation_gradient": rng.random((N, dimension * dimension)),
    }


def write_result(out_dir, dimension: int, status: str | None = "complete"):
    """Three frames and 30 series rows; closed with `status` (None: by leaving the with block)."""
    with ResultWriter(out_dir, small_scene(dimension), "9.9.9") as writer:
        for k, (step, time) in enumerate(zip(STEPS, TIMES)):
            for j in range(10):
                writer.append_series(time=time + j * 0.005, dt=0.005, kinetic_energy=1.0 + j,
                                     strain_energy=0.5, total_energy=1.5 + j)
            writer.write_frame(step, time, frame_fields(dimension, k))
        if status is not None:
            writer.close(status)
    return out_dir / "result.h5"


@pytest.mark.parametrize("dimension", [1, 2, 3])
def test_layout_names_attrs_shapes_and_dtypes(tmp_path, dimension):
    path = write_result(tmp_path, dimension)
    scene = small_scene(dimension)
    with h5py.File(path, "r") as h5:
        assert h5.attrs["format"] == "mpm-result"
        assert h5.attrs["format_version"] == 1
        assert json.loads(h5.attrs["scene"]) == json.loads(scene.model_dump_json())
        assert h5.attrs["dimension"] == dimension
        assert h5.attrs["solver_version"] == "9.9.9"
        assert h5.attrs["status"] == "complete"
        assert sorted(h5["frames"]) == ["000000", "000001", "000002"]
        for k, name in enumerate(sorted(h5["frames"])):
            frame = h5["frames"][name]
            assert frame.attrs["time"] == TIMES[k] and frame.attrs["step"] == STEPS[k]
            expected = {
                "id": ((N,), np.int64), "body": ((N,), np.int32), "mass": ((N,), np.float64),
                "position": ((N, dimension), np.float64), "velocity": ((N, dimension), np.float64),
                "stress": ((N, 6), np.float64), "von_mises": ((N,), np.float64),
                "deformation_gradient": ((N, dimension * dimension), np.float64),
            }
            assert set(frame) == set(expected)
            for key, (shape, dtype) in expected.items():
                assert frame[key].shape == shape, key
                assert frame[key].dtype == dtype, key
            np.testing.assert_array_equal(frame["stress"][()], frame_fields(dimension, k)["stress"])
        series = h5["time_series"]
        assert set(series) == {"time", "dt", "kinetic_energy", "strain_energy", "total_energy"}
        for key in series:
            assert series[key].shape == (30,) and series[key].dtype == np.float64
        np.testing.assert_allclose(series["kinetic_energy"][:10], np.arange(1.0, 11.0))


def test_leaving_the_with_block_normally_marks_complete(tmp_path):
    path = write_result(tmp_path, 2, status=None)
    with h5py.File(path, "r") as h5:
        assert h5.attrs["status"] == "complete"


def test_an_exception_in_the_with_block_marks_partial_and_keeps_frames(tmp_path):
    with pytest.raises(RuntimeError, match="boom"):
        with ResultWriter(tmp_path, small_scene(2), "0") as writer:
            writer.write_frame(0, 0.0, frame_fields(2, 0))
            raise RuntimeError("boom")
    with h5py.File(tmp_path / "result.h5", "r") as h5:
        assert h5.attrs["status"] == "partial"
        assert list(h5["frames"]) == ["000000"]
    assert (tmp_path / "result.xdmf").is_file()


def test_explicit_partial_close_is_kept_when_the_block_ends(tmp_path):
    path = write_result(tmp_path, 2, status="partial")
    with h5py.File(path, "r") as h5:
        assert h5.attrs["status"] == "partial"


def test_a_killed_writer_leaves_a_readable_partial_file(tmp_path):
    """The process dies without closing: the flushed frames and series are there."""
    script = textwrap.dedent(f"""
        import os, sys
        sys.path.insert(0, {str(__file__.rsplit('/', 1)[0])!r})
        from test_results import ResultWriter, frame_fields, small_scene
        writer = ResultWriter({str(tmp_path)!r}, small_scene(2), "0")
        writer.append_series(time=0.0, dt=0.1, kinetic_energy=1.0)
        writer.write_frame(0, 0.0, frame_fields(2, 0))
        writer.write_frame(7, 0.7, frame_fields(2, 1))
        os._exit(1)
    """)
    subprocess.run([sys.executable, "-c", script], check=False, timeout=120)
    path = tmp_path / "result.h5"
    with h5py.File(path, "r") as h5:
        assert h5.attrs["status"] == "partial"
    assert [f["step"] for f in list_frames(path)] == [0, 7]
    assert read_series(path)["kinetic_energy"].tolist() == [1.0]
    assert not (tmp_path / "result.xdmf").exists()


def test_another_process_reads_the_file_while_it_is_written(tmp_path):
    writer = ResultWriter(tmp_path, small_scene(2), "0")
    writer.write_frame(0, 0.0, frame_fields(2, 0))
    probe = (f"import h5py; f = h5py.File({str(tmp_path / 'result.h5')!r}, 'r'); "
             "print(f.attrs['status'], len(f['frames']))")
    seen = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True, timeout=60)
    assert seen.stdout.split() == ["partial", "1"], seen.stderr
    assert len(list_frames(tmp_path / "result.h5")) == 1  # in-process reader too
    writer.close("complete")


def test_series_keys_that_appear_later_are_padded_with_nan(tmp_path):
    with ResultWriter(tmp_path, small_scene(1), "0") as writer:
        writer.append_series(time=0.0, dt=0.1)
        writer.write_frame(0, 0.0, frame_fields(1, 0))
        writer.append_series(time=0.1, dt=0.1, plastic_work=2.0)
        writer.append_series(time=0.2, dt=0.1, plastic_work=3.0)
    series = read_series(tmp_path / "result.h5")
    assert series["time"].tolist() == [0.0, 0.1, 0.2]
    assert math.isnan(series["plastic_work"][0]) and series["plastic_work"][1:].tolist() == [2.0, 3.0]


@pytest.mark.parametrize("change, message", [
    (lambda f: f.pop("mass"), "mass"),
    (lambda f: f.update(position=np.zeros((N, 3))), "position"),
    (lambda f: f.update(stress=np.zeros((N, 3, 3))), "stress"),
    (lambda f: f.update(velocity=np.zeros((N - 1, 2))), "velocity"),
])
def test_write_frame_rejects_bad_fields_naming_them(tmp_path, change, message):
    fields = frame_fields(2, 0)
    change(fields)
    with ResultWriter(tmp_path, small_scene(2), "0") as writer:
        with pytest.raises(ValueError, match=message):
            writer.write_frame(0, 0.0, fields)


def test_readers(tmp_path):
    path = write_result(tmp_path, 2)
    assert [(f["index"], f["time"], f["step"], f["particles"]) for f in list_frames(path)] == [
        (0, 0.0, 0, N), (1, 0.05, 50, N), (2, 0.1, 100, N)]
    assert list_frames(path)[0]["fields"] == sorted(frame_fields(2, 0))
    last = read_frame(path)
    assert (last["index"], last["name"], last["time"], last["step"]) == (2, "000002", 0.1, 100)
    np.testing.assert_array_equal(last["fields"]["position"], frame_fields(2, 2)["position"])
    assert read_frame(path, 0)["fields"]["id"].tolist() == list(range(N))[::-1]
    assert read_frame(path, -3)["index"] == 0
    with pytest.raises(IndexError, match="3 frames"):
        read_frame(path, 3)
    assert read_scene(path)["name"] == "test-2d"
    assert read_series(path)["time"].shape == (30,)


def test_read_frame_with_max_rows_reads_every_kth_particle(tmp_path):
    """What a preview of a large frame reads (solver/preview.py): the least k whose every k-th
    row keeps to max_rows, the same rows of every field."""
    path = write_result(tmp_path, 2)
    whole = read_frame(path)["fields"]
    for max_rows, every in ((N, 1), (N - 1, 2), (N // 3, 3)):
        part = read_frame(path, max_rows=max_rows)
        assert part["every"] == every
        for name, values in whole.items():
            np.testing.assert_array_equal(part["fields"][name], values[::every])
            assert len(part["fields"][name]) <= max_rows


def test_readers_reject_other_hdf5_files(tmp_path):
    with h5py.File(tmp_path / "other.h5", "w") as h5:
        h5["x"] = [1.0]
    with pytest.raises(ValueError, match="not an MPM result"):
        list_frames(tmp_path / "other.h5")


# -- XDMF ----------------------------------------------------------------------------


def data_items(element):
    """(Dimensions, 'file:/path') of every HDF DataItem under `element`."""
    return [(tuple(int(d) for d in item.get("Dimensions").split()), item.text.strip())
            for item in element.iter("DataItem") if item.get("Format") == "HDF"]


@pytest.mark.parametrize("dimension", [1, 2, 3])
def test_xdmf_is_a_temporal_collection_pointing_at_existing_datasets(tmp_path, dimension):
    path = write_result(tmp_path, dimension)
    root = ET.parse(tmp_path / "result.xdmf").getroot()
    assert root.tag == "Xdmf" and root.get("Version") == "3.0"
    (collection,) = root.find("Domain").findall("Grid")
    assert (collection.get("GridType"), collection.get("CollectionType")) == ("Collection", "Temporal")
    grids = collection.findall("Grid")
    assert [float(g.find("Time").get("Value")) for g in grids] == TIMES
    with h5py.File(path, "r") as h5:
        for k, grid in enumerate(grids):
            topology = grid.find("Topology")
            assert topology.get("TopologyType") == "Polyvertex"
            assert topology.get("NumberOfElements") == str(N)
            geometry = grid.find("Geometry")
            assert geometry.get("GeometryType") == {1: "XYZ", 2: "XY", 3: "XYZ"}[dimension]
            for dims, ref in data_items(grid):
                filename, dataset = ref.split(":", 1)
                assert filename == "result.h5"
                assert dataset in h5, dataset
                assert dims[0] == h5[dataset].shape[0] and math.prod(dims) == h5[dataset].size, ref
            (geometry_dims, geometry_ref), = data_items(geometry)
            xyz = h5[geometry_ref.split(":", 1)[1]][()]
            position = h5[f"frames/{k:06d}/position"][()]
            np.testing.assert_array_equal(xyz[:, :dimension], position)
            if dimension == 1:  # padded with zeros to x, y, z
                assert xyz.shape == (N, 3) and not xyz[:, 1:].any()
            attributes = {a.get("Name"): a.get("AttributeType") for a in grid.findall("Attribute")}
            vector = "Scalar" if dimension == 1 else "Vector"
            assert attributes == {
                "id": "Scalar", "body": "Scalar", "mass": "Scalar", "von_mises": "Scalar",
                "velocity": vector, "stress": "Matrix",
                "deformation_gradient": "Scalar" if dimension == 1 else "Matrix",
            }
    assert not list(tmp_path.glob(".result.xdmf*"))  # the temporary file of the atomic write is gone


class _Blocks(dict):
    """Fields given by `blocks` of 5 rows (the last shorter), as solver/fields.py FrameFields
    gives a field of each particle's own state."""

    def blocks(self, key):
        values = self[key]
        if key in ("id", "body"):
            yield 0, values
            return
        for start in range(0, len(values), 5):
            yield start, values[start:start + 5]


def test_a_field_written_in_blocks_is_the_field_written_whole(tmp_path):
    fields = frame_fields(3, 0)
    assert len(fields["id"]) % 5 != 0   # (a short last block)
    for name, given in (("whole", dict(fields)), ("blocks", _Blocks(fields))):
        with ResultWriter(tmp_path / name, small_scene(3), "test") as writer:
            writer.write_frame(1, 0.5, given)
    whole, blocks = read_frame(tmp_path / "whole" / "result.h5", 0), read_frame(tmp_path / "blocks" / "result.h5", 0)
    for key, values in whole["fields"].items():
        assert np.array_equal(blocks["fields"][key], values) and blocks["fields"][key].dtype == values.dtype, key


def test_blocks_that_do_not_cover_the_particles_leave_no_frame(tmp_path):
    fields = _Blocks(frame_fields(2, 0))
    fields["stress"] = fields["stress"][:-1]
    with ResultWriter(tmp_path, small_scene(2), "test") as writer:
        with pytest.raises(ValueError, match="field 'stress' has .* rows, expected"):
            writer.write_frame(1, 0.5, fields)
        assert writer.frame_count == 0
    assert list_frames(tmp_path / "result.h5") == []
