"""The `mesh` geometry: STL (binary, ASCII) and OBJ readers, the inside test, and the
errors a bad mesh gets (each naming its field), before any particle is allocated."""
from __future__ import annotations

import base64
import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "verification"))
from mesh_shapes import ascii_stl, binary_stl, cube, icosphere, obj  # noqa: E402

from solver import mesh  # noqa: E402
from solver.scene_checks import load_scene  # noqa: E402
from solver.seeding import seed  # noqa: E402
from tests.scene_errors import errors_of


def mesh_scene(geometry: dict) -> dict:
    return {
        "dimension": 3,
        "grid": {"lower": [-1.2] * 3, "upper": [1.2] * 3, "cell_size": 0.2},
        "materials": {"m": {"model": "linear_elastic", "density": 1000, "youngs_modulus": 1e6, "poisson_ratio": 0.3}},
        "bodies": [{"name": "part", "material": "m", "geometry": geometry}],
        "time": {"end": 0.01},
    }


def data_geometry(raw: bytes, fmt: str = "stl", **extra) -> dict:
    return {"type": "mesh", "data": base64.b64encode(raw).decode(), "format": fmt, **extra}



@pytest.mark.parametrize("writer,fmt", [(binary_stl, "stl"), (ascii_stl, "stl"), (obj, "obj")])
def test_the_three_formats_read_the_same_triangles(writer, fmt):
    triangles = icosphere(1)
    read = mesh.read_triangles(writer(triangles), fmt)
    # binary STL stores float32: the corners agree to its precision; ASCII and OBJ exactly (repr)
    assert read.shape == triangles.shape
    np.testing.assert_allclose(np.sort(read.reshape(-1, 3), axis=0), np.sort(triangles.reshape(-1, 3), axis=0),
                               rtol=0, atol=1e-7 if writer is binary_stl else 0)


def test_a_binary_stl_whose_header_starts_with_solid_is_read_as_binary():
    triangles = cube()
    assert np.array_equal(mesh.read_triangles(binary_stl(triangles, b"solid by a CAD tool"), "stl"), triangles)


def test_obj_polygons_are_split_into_triangles():
    square_prism = b"""v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1
f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n"""
    triangles = mesh.read_triangles(square_prism, "obj")
    assert triangles.shape == (12, 3, 3) and mesh.open_edges(triangles) == 0


def test_inside_agrees_with_the_convex_planes_of_an_icosphere():
    """A convex mesh: inside exactly where every face's plane has the point behind it.
    Points within 1e-9 of a plane are left out (either answer is right on the surface)."""
    triangles = icosphere(3)
    points = np.random.default_rng(1).uniform(-1.1, 1.1, (40_000, 3))
    normal = np.cross(triangles[:, 1] - triangles[:, 0], triangles[:, 2] - triangles[:, 0])
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    offset = np.einsum("ij,ij->i", normal, triangles[:, 0])
    clear, expected = [], []
    for chunk in np.array_split(points, 8):
        height = chunk @ normal.T - offset[None, :]
        clear.append(np.all(np.abs(height) > 1e-9, axis=1))
        expected.append(np.all(height < 0, axis=1))
    clear, expected = np.concatenate(clear), np.concatenate(expected)
    got = mesh.Mesh(triangles).contains(points)
    assert clear.sum() > 39_000 and expected.sum() > 10_000 and np.array_equal(got[clear], expected[clear])


def test_lattice_points_on_edges_and_vertices_count_once():
    """Points exactly on the cube's edges, face diagonals and corners (a lattice that
    contains them): the crossing count never double counts, so every point strictly
    inside is inside and every point strictly outside is outside."""
    axis = np.linspace(-1, 1, 41)
    points = np.stack(np.meshgrid(axis, axis, axis, indexing="ij"), axis=-1).reshape(-1, 3)
    got = mesh.Mesh(cube([-0.5] * 3, [0.5] * 3)).contains(points)
    assert np.all(got[np.all(np.abs(points) < 0.5, axis=1)])
    assert not np.any(got[np.any(np.abs(points) > 0.5, axis=1)])


def test_orientation_does_not_matter():
    triangles = icosphere(2)
    flipped = triangles.copy()
    flipped[::3] = flipped[::3, ::-1]     # a third of the faces turned inside out
    points = np.random.default_rng(2).uniform(-1.1, 1.1, (50_000, 3))
    assert np.array_equal(mesh.Mesh(triangles).contains(points), mesh.Mesh(flipped).contains(points))


def test_a_file_mesh_is_read_beside_the_scene_file_scaled_and_translated(tmp_path):
    (tmp_path / "parts").mkdir()
    (tmp_path / "parts" / "cube.stl").write_bytes(ascii_stl(cube()))
    scene = mesh_scene({"type": "mesh", "file": "parts/cube.stl", "scale": 0.8, "translate": [-0.4, -0.4, -0.4]})
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(scene))
    loaded = load_scene(path)
    lower, upper = loaded.bodies[0].geometry.shape().bounding_box()
    assert np.allclose(lower, -0.4) and np.allclose(upper, 0.4)
    seeds = seed(loaded)
    assert seeds.volume.sum() == pytest.approx(0.8**3)   # the cube's faces lie on cell faces: exact
    # the dumped scene names the file by its absolute path: it reloads from anywhere
    assert load_scene(loaded.model_dump(mode="json"), files=Path("/")).bodies[0].geometry.shape() is not None


def test_a_file_mesh_in_a_document_is_refused_without_opening_it(tmp_path):
    scene = mesh_scene({"type": "mesh", "file": str(tmp_path / "does-not-matter.stl")})
    [error] = errors_of(scene)
    assert error["path"] == "bodies[0].geometry.file" and "send the file's bytes as \"data\"" in error["message"]


def test_an_open_mesh_names_its_open_edges():
    triangles = cube()[:-1]                 # one triangle missing: its 3 edges are open
    [error] = errors_of(mesh_scene(data_geometry(binary_stl(triangles))))
    assert error == {"path": "bodies[0].geometry.data",
                     "message": "mesh is not closed: 3 open edges (edges of only one triangle); a body needs a "
                                "closed (watertight) surface"}


@pytest.mark.parametrize("raw,fmt,message", [
    (b"solid empty\nendsolid empty\n", "stl", "the STL mesh has no triangles"),
    (b"v 0 0 0\n", "obj", "the OBJ mesh has no triangles"),
    (b"f 1 2 3\n", "obj", "line 1: a face refers to a vertex that does not exist (0 vertices)"),
    (b"\x00" * 80 + b"\x05\x00\x00\x00" + b"\x00" * 50, "stl",
     "is neither a binary STL (its 134 bytes do not match the 5 triangles its header announces (334 bytes)) "
     "nor an ASCII STL (text starting with 'solid')"),
])
def test_unreadable_or_empty_meshes(raw, fmt, message):
    [error] = errors_of(mesh_scene(data_geometry(raw, fmt)))
    assert error == {"path": "bodies[0].geometry.data", "message": message}


def test_base64_that_does_not_decode():
    [error] = errors_of(mesh_scene({"type": "mesh", "data": "not base64!", "format": "stl"}))
    assert error["path"] == "bodies[0].geometry.data" and error["message"].startswith("does not decode as base64")


def test_a_mesh_over_the_size_limit_is_refused_before_decoding(monkeypatch):
    raw = binary_stl(icosphere(2))          # 320 triangles: 16,084 bytes
    monkeypatch.setenv("MPM_MAX_MESH_BYTES", "10000")
    [error] = errors_of(mesh_scene(data_geometry(raw)))
    assert error["path"] == "bodies[0].geometry.data"
    assert "larger than the limit of 10000 bytes (MPM_MAX_MESH_BYTES)" in error["message"]
    monkeypatch.setenv("MPM_MAX_MESH_BYTES", str(len(raw)))
    load_scene(mesh_scene(data_geometry(raw)))


def test_a_mesh_outside_the_grid():
    [error] = errors_of(mesh_scene(data_geometry(binary_stl(cube()), translate=[0.5, 0, 0])))
    assert error["path"] == "bodies[0].geometry" and "extends outside the grid" in error["message"]


def test_file_and_data_format_and_dimension_rules():
    both = {"type": "mesh", "file": "a.stl", "data": "", "format": "stl"}
    assert errors_of(mesh_scene(both))[0]["path"] == "bodies[0].geometry.file"
    assert errors_of(mesh_scene({"type": "mesh", "data": ""}))[0] == {
        "path": "bodies[0].geometry.format", "message": "required: one of ['stl', 'obj']"}
    flat = mesh_scene(data_geometry(binary_stl(cube())))
    flat.update(dimension=2, grid={"lower": [-1, -1], "upper": [1, 1], "cell_size": 0.2})
    assert errors_of(flat) == [{"path": "bodies[0].geometry.type",
                                "message": "a mesh is a 3D geometry; this scene is 2D (use a polygon in 2D)"}]


def test_the_service_answers_422_to_a_file_mesh_and_accepts_its_data(tmp_path):
    from service.errors import ApiError
    from service.scenes import check_scene
    from service.settings import ApiSettings

    (tmp_path / "cube.stl").write_bytes(binary_stl(cube([-0.4] * 3, [0.4] * 3)))
    with pytest.raises(ApiError) as caught:
        check_scene(mesh_scene({"type": "mesh", "file": str(tmp_path / "cube.stl")}), ApiSettings())
    assert caught.value.status == 422 and caught.value.details[0]["path"] == "bodies[0].geometry.file"
    inlined = mesh.inline_files(mesh_scene({"type": "mesh", "file": "cube.stl"}), tmp_path)
    _, summary = check_scene(inlined, ApiSettings())
    assert summary["particles"] == 4**3 * 8   # 0.8 m cube, 0.2 m cells, 2 particles per cell per axis
