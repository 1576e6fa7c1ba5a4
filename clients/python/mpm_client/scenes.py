"""Turn what a caller hands to ``submit``/``validate`` into the scene document to send.

Accepted: a dict, a path to a ``.json`` file (``.yaml``/``.yml`` when PyYAML is
installed), JSON text, or any pydantic model such as the solver's ``Scene``
(the SDK does not import the solver; it only calls ``model_dump``).
"""
from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any, Union

SceneLike = Union[dict, str, "os.PathLike[str]", Any]


def scene_document(scene: SceneLike) -> dict:
    """The scene as a JSON-ready dict; raises ``ValueError``/``FileNotFoundError`` naming the problem."""
    if isinstance(scene, dict):
        return scene
    if hasattr(scene, "model_dump"):  # a pydantic model, e.g. solver.scene.Scene
        return scene.model_dump(mode="json", by_alias=True, exclude_none=True)
    if isinstance(scene, str) and scene.lstrip().startswith("{"):
        return _parse_json(scene, "the scene text")
    if isinstance(scene, (str, os.PathLike)):
        return _read_file(Path(scene))
    raise TypeError(f"a scene is a dict, a file path, JSON text or a pydantic model, not {type(scene).__name__}")


def _read_file(path: Path) -> dict:
    if not path.is_file():
        raise FileNotFoundError(f"scene file not found: {path}")
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


def _parse_json(text: str, where: str) -> dict:
    try:
        document = json.loads(text)
    except json.JSONDecodeError as exc:
        raise ValueError(f"{where} is not valid JSON: line {exc.lineno}, column {exc.colno}: {exc.msg}") from None
    if not isinstance(document, dict):
        raise ValueError(f"{where}: a scene is a JSON object, not {type(document).__name__}")
    return document
