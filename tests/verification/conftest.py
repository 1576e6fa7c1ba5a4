import pytest

from mpm_cases import run_scene


@pytest.fixture
def run_case(tmp_path):
    """run_case(scene, name) runs a scene into a temporary folder and returns a Case."""
    def _run(scene, name="case"):
        return run_scene(scene, tmp_path / name)

    return _run
