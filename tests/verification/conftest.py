import pytest

from mpm_cases import Case


@pytest.fixture
def run_case(tmp_path):
    """run_case(scene, name) runs a scene into a temporary folder and returns a Case."""
    from solver import run

    def _run(scene, name="case"):
        return Case(run(scene, tmp_path / name))

    return _run
