"""The validation errors a scene gets: `errors_of(scene)` is the list of {"path", "message"}
that load_scene raises with (the test fails if it loads)."""
from __future__ import annotations

import pytest

from solver.scene import SceneError
from solver.scene_checks import load_scene


def errors_of(scene, **options) -> list[dict]:
    with pytest.raises(SceneError) as caught:
        load_scene(scene, **options)
    return caught.value.errors
