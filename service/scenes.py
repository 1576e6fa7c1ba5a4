"""Scene validation for the API (solver.scene_checks, solver.summary) and the scene routes:
validate, a Karamelo input file imported, the JSON Schema, the built-in examples."""
from __future__ import annotations

from dataclasses import asdict
from functools import lru_cache
from pathlib import PurePath
from typing import Any

from fastapi import APIRouter, Body, Depends
from pydantic import BaseModel, ConfigDict, Field, model_validator
from pydantic_core import PydanticCustomError

from solver import capabilities
from solver.karamelo import KarameloError, translate
from solver.examples import ExampleNotFound, list_examples, load_example
from solver.scene import Scene, SceneError
from solver.scene_checks import Limits, load_scene
from solver.summary import empty_bodies, summarize

from service.auth import caller
from service.errors import ApiError, documented, validation_error
from service.settings import ApiSettings
from service.state import Services, services

router = APIRouter(tags=["scenes"], dependencies=[Depends(caller)])


def check_scene(document: dict[str, Any], settings: ApiSettings) -> tuple[str, dict[str, Any]]:
    """The validated scene as JSON text, and its summary; 422 with every error.

    The limits (MPM_MAX_PARTICLES, MPM_MAX_MEMORY_BYTES, ...) are checked on counts
    computed from the scene, before anything is allocated; their errors name the setting.
    A body that seeds no particle is refused by name (the run would have nothing to move)."""
    try:
        scene = load_scene(document, stability=False)
    except SceneError as exc:
        raise validation_error(exc.errors, "the scene is not valid") from None
    except ArithmeticError as exc:   # a rule's arithmetic overflowed on an absurd value: never a 500
        raise validation_error([_out_of_range(exc)], "the scene is not valid") from None
    limits = Limits(max_particles=settings.max_particles, max_grid_nodes=settings.max_grid_nodes,
                    max_steps=settings.max_steps, max_memory_bytes=settings.max_memory_bytes)
    try:
        load_scene(scene, limits=limits)   # the limits, then (within them) the time step's stability
        summary = summarize(scene).model_dump(mode="json")
    except SceneError as exc:
        details = [_with_setting(error) for error in exc.errors]
        over = any(detail["limit"] for detail in details)
        raise validation_error(details, "the scene is over the service's limits" if over
                               else "the scene is not valid") from None
    except ArithmeticError as exc:
        raise validation_error([_out_of_range(exc)], "the scene is not valid") from None
    empty = empty_bodies(scene, summary["particles_per_body"])
    if empty:
        raise validation_error([{"path": path, "message": message} for path, message in empty],
                               "the scene is not valid")
    return scene.model_dump_json(), summary


def _with_setting(error: dict[str, Any]) -> dict[str, Any]:
    """A limit error names its setting (max_particles -> MPM_MAX_PARTICLES); others get limit None."""
    setting = f"MPM_{error['limit'].upper()}" if error.get("limit") else None
    message = f"{error['message']} ({setting})" if setting else error["message"]
    return {**error, "message": message, "limit": setting}


def _out_of_range(exc: ArithmeticError) -> dict[str, str]:
    return {"path": "", "message": f"a number of the scene is out of the range of double precision arithmetic "
                                   f"({type(exc).__name__}: {exc}); use values of sensible magnitude"}


class WrapsScene(BaseModel):
    """A request body that carries a scene under `scene` (a job, a sweep). A bare scene posted
    in its place is answered with one error that says how to wrap it, rather than a list of
    "Extra inputs are not permitted" for each of its keys (the contract keeps the wrapper:
    a mistyped `scene` key must not be read as a scene)."""

    @model_validator(mode="before")
    @classmethod
    def _not_a_bare_scene(cls, body: Any) -> Any:
        if isinstance(body, dict) and "scene" not in body:
            scene_keys = (set(Scene.model_fields) - set(cls.model_fields)) & set(body)
            if scene_keys:
                raise PydanticCustomError(
                    "bare_scene", "this body is a bare scene (it has {keys}); send the scene wrapped, "
                    "{wrapped}, with the request's other keys ({others}) beside it",
                    {"keys": ", ".join(sorted(scene_keys)), "wrapped": '{"scene": <the scene>}',
                     "others": ", ".join(key for key in cls.model_fields if key != "scene")})
        return body


def granted_processes(requested: int | None, scene: dict[str, Any], settings: ApiSettings) -> int:
    """The processes a job runs on: what it asks (the request, else the scene), capped by
    MPM_MAX_PROCESSES and by what the solver supports."""
    asked = requested or (scene.get("parallel") or {}).get("processes") or 1
    return max(1, min(asked, settings.max_processes, capabilities.MAX_PROCESSES))


@router.post("/v1/scenes/validate",
             responses=documented({413: "request over MPM_MAX_BODY_BYTES",
                                   422: "every validation error, path and message"}))
def validate_scene(scene: dict[str, Any] = Body(..., description="a scene document"),
                   svc: Services = Depends(services)) -> dict[str, Any]:
    """Validate a scene; answer what it implies (particles, nodes, steps, memory, run time)."""
    if isinstance(scene.get("scene"), dict) and not set(scene) & set(Scene.model_fields):
        raise validation_error([{"path": "scene", "message": "this body is a job request; /v1/scenes/validate "
                                 "takes the scene itself, not wrapped in {\"scene\": ...}"}],
                               "the scene is not valid")
    _, summary = check_scene(scene, svc.settings)
    return {"summary": summary}


class KarameloFile(BaseModel):
    """A Karamelo input file sent for import (JSON like every request body of the API)."""
    model_config = ConfigDict(extra="forbid")
    text: str = Field(description="the file's text")
    name: str = Field("karamelo", max_length=200,
                      description="the file's name (its stem names the scene, as `mpm import karamelo` does)")


@router.post("/v1/scenes/import/karamelo",
             responses=documented({413: "request over MPM_MAX_BODY_BYTES",
                                   422: "a line the importer cannot read, by its number"}))
def import_karamelo(file: KarameloFile) -> dict[str, Any]:
    """A Karamelo input file imported into a scene, as `mpm import karamelo` does: the scene
    (not validated: validate or submit it next), the lines left out and the lines translated
    with a difference, each with its number, its text and the reason."""
    try:
        translation = translate(file.text, name=PurePath(file.name).stem or "karamelo")
    except KarameloError as exc:
        raise validation_error([{"path": "text", "message": str(exc)}], "the Karamelo file cannot be imported") from None
    return {"scene": translation.scene, "untranslated": [asdict(item) for item in translation.untranslated],
            "notes": [asdict(item) for item in translation.notes]}


@lru_cache
def _scene_schema() -> dict[str, Any]:
    return Scene.model_json_schema()


@router.get("/v1/schema/scene")
def scene_schema() -> dict[str, Any]:
    """The JSON Schema of a scene document."""
    return _scene_schema()


@router.get("/v1/examples")
def examples() -> dict[str, Any]:
    """The built-in example scenes."""
    return {"examples": [{key: example[key] for key in ("name", "title", "dimension")}
                         for example in list_examples()]}  # not the server's file paths


@router.get("/v1/examples/{name}", responses=documented({404: "no such example"}))
def example(name: str) -> dict[str, Any]:
    """One built-in example scene, as a document ready to submit."""
    try:
        return load_example(name)
    except ExampleNotFound as exc:
        raise ApiError(404, "not_found", str(exc)) from None
