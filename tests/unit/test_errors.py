"""The solver's own errors share one base class and keep the built-in class they had."""
import pytest

from solver.checkpoint import CheckpointError
from solver.errors import SolverError
from solver.examples import ExampleNotFound, load_example
from solver.expressions import ExpressionError, compile_expression
from solver.preview import UnknownField
from solver.results import FrameNotFound
from solver.scene import SceneError
from solver.scene_checks import load_scene
from solver.stepper import Instability


@pytest.mark.parametrize("error,builtin", [
    (SceneError, ValueError), (ExpressionError, ValueError), (CheckpointError, ValueError),
    (ExampleNotFound, KeyError), (Instability, RuntimeError), (FrameNotFound, IndexError), (UnknownField, ValueError)])
def test_every_solver_error_is_a_solver_error(error, builtin):
    assert issubclass(error, SolverError) and issubclass(error, builtin)


def test_callers_catch_the_base_and_read_fields_not_text():
    with pytest.raises(SolverError) as scene:
        load_scene({"dimension": 2})
    assert {e["path"] for e in scene.value.errors} >= {"grid", "materials", "bodies"}
    with pytest.raises(SolverError):
        compile_expression("sin(", ("x",))
    with pytest.raises(SolverError):
        load_example("no_such_example")
    unstable = Instability(12, 0.5, 7, "J = det F", "-0.1 <= 0")
    assert (unstable.step, unstable.particle_id, unstable.quantity) == (12, 7, "J = det F")
