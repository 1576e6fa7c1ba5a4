"""The `points` geometry: particles given by positions and volumes, inline or from a CSV or
HDF5 file; they are seeded as given, and bad input is refused at its path."""
from __future__ import annotations

import json

import h5py
import numpy as np
import pytest

from solver.scene import SceneError
from solver.scene_checks import load_scene
from solver.seeding import count_particles, seed
from tests.scene_errors import errors_of

POSITIONS = [[0.15, 0.15], [0.55, 0.25], [0.35, 0.75]]   # cells apart: they do not touch
VOLUMES = [1e-4, 2e-4, 3e-4]


def points_scene(geometry: dict) -> dict:
    return {
        "dimension": 2,
        "grid": {"lower": [0, 0], "upper": [1, 1], "cell_size": 0.1},
        "materials": {"m": {"model": "linear_elastic", "density": 1000, "youngs_modulus": 1e6, "poisson_ratio": 0.3}},
        "bodies": [{"name": "cloud", "material": "m", "geometry": geometry}],
        "time": {"end": 0.01},
    }



def test_inline_points_are_the_particles():
    scene = load_scene(points_scene({"type": "points", "positions": POSITIONS, "volumes": VOLUMES}))
    seeds = seed(scene)
    assert np.array_equal(seeds.position, POSITIONS) and np.array_equal(seeds.volume, VOLUMES)
    assert count_particles(scene) == [3]


@pytest.mark.parametrize("suffix", [".csv", ".h5"])
def test_a_points_file_beside_the_scene(tmp_path, suffix):
    columns = {"volume": VOLUMES, "y": [p[1] for p in POSITIONS], "x": [p[0] for p in POSITIONS]}
    if suffix == ".csv":   # columns in any order, named by the header
        rows = ["volume, y, x"] + [f"{v!r},{y!r},{x!r}" for v, y, x in zip(*columns.values())]
        (tmp_path / f"cloud{suffix}").write_text("\n".join(rows) + "\n")
    else:
        with h5py.File(tmp_path / f"cloud{suffix}", "w") as handle:
            for name, values in columns.items():
                handle[name] = values
    path = tmp_path / "scene.json"
    path.write_text(json.dumps(points_scene({"type": "points", "file": f"cloud{suffix}"})))
    seeds = seed(load_scene(path))
    assert np.array_equal(seeds.position, POSITIONS) and np.array_equal(seeds.volume, VOLUMES)


def test_points_errors():
    assert errors_of(points_scene({"type": "points", "positions": POSITIONS, "volumes": VOLUMES[:2]})) == [
        {"path": "bodies[0].geometry.volumes", "message": "3 positions but 2 volumes"}]
    assert errors_of(points_scene({"type": "points", "positions": POSITIONS}))[0]["path"] == "bodies[0].geometry.volumes"
    assert errors_of(points_scene({"type": "points", "file": "/etc/hostname"}))[0]["message"].startswith(
        "a scene sent as a document cannot name a file")
    assert errors_of(points_scene({"type": "points", "positions": [[0.1, 0.2, 0.3]], "volumes": [1e-3]})) == [
        {"path": "bodies[0].geometry.positions", "message": "the points have 3 coordinates; the scene is 2D"}]
    outside = errors_of(points_scene({"type": "points", "positions": [[1.5, 0.5]], "volumes": [1e-3]}))
    assert outside[0]["path"] == "bodies[0].geometry" and "outside the grid" in outside[0]["message"]
    combined = points_scene({"type": "union", "parts": [{"type": "points", "positions": POSITIONS, "volumes": VOLUMES}]})
    assert errors_of(combined)[0]["path"] == "bodies[0].geometry.parts[0].type"
    traction = points_scene({"type": "points", "positions": POSITIONS, "volumes": VOLUMES})
    traction["loads"] = [{"type": "traction", "body": "cloud", "where": {"type": "box", "lower": [0, 0], "upper": [1, 1]},
                          "traction": [1, 0]}]
    assert errors_of(traction)[0]["path"] == "loads[0].type"


def test_a_points_body_runs(tmp_path):
    from solver import run

    scene = points_scene({"type": "points", "positions": POSITIONS, "volumes": VOLUMES})
    scene["bodies"][0]["initial_velocity"] = [1.0, 0.0]
    scene["output"] = {"frames": 2, "fields": ["position", "mass"]}
    scene["time"] = {"end": 0.01, "dt": 0.001}
    result = run(scene, tmp_path)
    assert result.status == "complete"
    with h5py.File(tmp_path / "result.h5") as handle:
        last = handle["frames"][sorted(handle["frames"])[-1]]
        assert np.allclose(last["mass"][:], 1000 * np.array(VOLUMES))
        assert np.allclose(last["position"][:, 0], np.array(POSITIONS)[:, 0] + 0.01)   # free flight at 1 m/s


def test_a_points_file_over_the_limit_or_without_its_columns(tmp_path, monkeypatch):
    (tmp_path / "cloud.csv").write_text("x,y,volume\n" + "0.5,0.5,0.001\n" * 100)
    (tmp_path / "bare.csv").write_text("x,y\n0.5,0.5\n")
    for name in ("cloud", "bare"):
        (tmp_path / f"{name}.json").write_text(json.dumps(points_scene({"type": "points", "file": f"{name}.csv"})))
    with pytest.raises(SceneError) as caught:
        load_scene(tmp_path / "bare.json")
    assert caught.value.errors[0]["path"] == "bodies[0].geometry.file"
    assert "needs columns x, y[, z] and volume; it has ['x', 'y']" in caught.value.errors[0]["message"]
    monkeypatch.setenv("MPM_MAX_MESH_BYTES", "1000")
    with pytest.raises(SceneError) as caught:
        load_scene(tmp_path / "cloud.json")
    assert "the points file" in caught.value.errors[0]["message"]
    assert "larger than the limit of 1000 bytes (MPM_MAX_MESH_BYTES)" in caught.value.errors[0]["message"]
