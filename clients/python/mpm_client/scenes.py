"""Turn what a caller hands to ``submit``/``validate`` into the scene document to send.

Accepted: a dict, a path to a ``.json`` file (``.yaml``/``.yml`` when PyYAML is
installed), JSON text, or any pydantic model such as the solver's ``Scene``
(the SDK does not import the solver; it only calls ``model_dump``), or a Karamelo
input file (``.mpm``), imported into a scene by the solver's importer where the solver
is installed (its notes and left-out lines are warnings).

The service never opens a path named in a scene, so a geometry that names a local
file (``{"type": "mesh", "file": "part.stl"}``) is sent with the file's bytes inlined
as ``"data"`` (base64) and its ``"format"``, a points file (CSV, or HDF5 with h5py
installed) as its ``"positions"`` and ``"volumes"``: names relative to the scene
file, or to the current folder for a scene given as a dict.
"""
from __future__ import annotations

import base64
import json
import os
import warnings
from pathlib import Path
from typing import Any, Union

SceneLike = Union[dict, str, "os.PathLike[str]", Any]


def scene_document(scene: SceneLike) -> dict:
    """The scene as a JSON-ready dict; raises ``ValueError``/``FileNotFoundError`` naming the problem."""
    if isinstance(scene, dict):
        return inline_files(scene, Path.cwd())
    if hasattr(scene, "model_dump"):  # a pydantic model, e.g. solver.scene.Scene
        return inline_files(scene.model_dump(mode="json", by_alias=True, exclude_none=True), Path.cwd())
    if isinstance(scene, str) and scene.lstrip().startswith("{"):
        return inline_files(_parse_json(scene, "the scene text"), Path.cwd())
    if isinstance(scene, (str, os.PathLike)):
        return inline_files(_read_file(Path(scene)), Path(scene).parent)
    raise TypeError(f"a scene is a dict, a file path, JSON text or a pydantic model, not {type(scene).__name__}")


def _read_file(path: Path) -> dict:
    if not path.is_file():
        raise FileNotFoundError(f"scene file not found: {path}")
    if path.suffix.lower() == ".mpm":
        return _karamelo(path)
    text = path.read_text(encoding="utf-8")
    if path.suffix.lower() in (".yaml", ".yml"):
        try:
            import yaml  # optional: the SDK depends only on httpx and pydantic
        except ImportError:
            raise ValueError(f"{path}: reading YAML scenes needs PyYAML (pip install pyyaml)") from None
        document = yaml.safe_load(text)
    else:
        document = _parse_json(text, str(path))
    if not isinstance(document, dict):
        raise ValueError(f"{path}: a scene is a JSON object, not {type(document).__name__}")
    return document


class KarameloImportWarning(UserWarning):
    """A line of a Karamelo file that the import left out or translated with a difference."""


def _karamelo(path: Path) -> dict:
    """A Karamelo input file imported into a scene (`mpm import karamelo`): each line it leaves
    out or notes is a KarameloImportWarning; a file it cannot import is a ValueError naming the line."""
    try:
        from solver.karamelo import KarameloError, translate_file
    except ImportError:
        raise ValueError(f"{path}: importing a Karamelo file needs the solver package (mpm-service), "
                         "or run `mpm import karamelo` where it is installed and submit the scene") from None
    try:
        translation = translate_file(path)
    except KarameloError as exc:
        raise ValueError(f"{path}: cannot import the Karamelo file: {exc}") from None
    for kind, items in (("note", translation.notes), ("not translated", translation.untranslated)):
        for item in items:
            warnings.warn(f"{path}:{item.line}: {kind}: {item.text + ': ' if item.text else ''}{item.reason}",
                          KarameloImportWarning, stacklevel=4)
    return translation.scene


def _parse_json(text: str, where: str) -> dict:
    try:
        document = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ValueError(f"{where} is not valid JSON: line {exc.lineno}, column {exc.colno}: {exc.msg}") from None
    if not isinstance(document, dict):
        raise ValueError(f"{where}: a scene is a JSON object, not {type(document).__name__}")
    return document


# Geometry types whose "file" is sent inlined, and the formats their file suffixes name.
MESH_FORMATS = {".stl": "stl", ".obj": "obj"}


def inline_files(document: Any, folder: Path) -> Any:
    """A copy of the document with every mesh geometry's "file" replaced by its bytes as
    "data" (base64) and "format"."""
    if isinstance(document, list):
        return [inline_files(item, folder) for item in document]
    if not isinstance(document, dict):
        return document
    items = {key: inline_files(value, folder) for key, value in document.items()}
    if items.get("type") == "mesh" and isinstance(items.get("file"), str):
        items = _inline_mesh(items, folder)
    if items.get("type") == "points" and isinstance(items.get("file"), str):
        items = _inline_points(items, folder)
    return items


def _inline_mesh(geometry: dict, folder: Path) -> dict:
    path = folder / geometry["file"]
    fmt = geometry.get("format") or MESH_FORMATS.get(path.suffix.lower())
    if fmt is None:
        raise ValueError(f"mesh file {path}: give \"format\" (its suffix names none of stl, obj)")
    try:
        raw = path.read_bytes()
    except OSError as exc:
        raise FileNotFoundError(f"mesh file {path}: {exc.strerror or exc}") from None
    inlined = {key: value for key, value in geometry.items() if key != "file"}
    inlined.update(data=base64.b64encode(raw).decode("ascii"), format=fmt)
    return inlined


def _inline_points(geometry: dict, folder: Path) -> dict:
    """{"type": "points", "file": F} -> positions and volumes read from F's columns x, y[, z], volume."""
    path = folder / geometry["file"]
    if not path.is_file():
        raise FileNotFoundError(f"points file not found: {path}")
    if path.suffix.lower() == ".csv":
        import csv

        with path.open(newline="", encoding="utf-8") as handle:
            rows = list(csv.reader(handle))
        names = [name.strip().lower() for name in rows[0]] if rows else []
        columns = {name: [float(row[k]) for row in rows[1:] if row] for k, name in enumerate(names)}
    else:
        try:
            import h5py  # optional: the SDK depends only on httpx and pydantic
        except ImportError:
            raise ValueError(f"{path}: reading an HDF5 points file needs h5py (pip install h5py)") from None
        with h5py.File(path, "r") as handle:
            columns = {name: [float(v) for v in handle[name][()].ravel()] for name in ("x", "y", "z", "volume")
                       if name in handle}
    axes = [name for name in ("x", "y", "z") if name in columns]
    if "volume" not in columns or not axes:
        raise ValueError(f"{path}: a points file needs columns x, y[, z] and volume")
    inlined = {key: value for key, value in geometry.items() if key != "file"}
    inlined.update(positions=[list(p) for p in zip(*(columns[a] for a in axes))], volumes=columns["volume"])
    return inlined
