"""Named sub-expressions (the scene's `expressions`): evaluated as if written out, once
each per evaluation; cycles, unknown names, too many and too deep chains refused with
the name and the rule."""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from solver.expressions import (MAX_DEFINITION_CHAIN, MAX_DEFINITIONS, MAX_LENGTH, ExpressionError,
                                compile_expression, definition_problems)
from solver.scene import SceneError
from solver.scene_checks import load_scene

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
DEFINITIONS = {"r": "sqrt(x*x + y*y)", "h": "1 - 8*r**2", "g": "sin(pi*t)", "alpha": "g*h"}


def test_a_named_expression_evaluates_as_written_out():
    x, y, t = np.linspace(0.1, 1, 7), np.linspace(-1, 0.3, 7), 0.3
    named = compile_expression("alpha*cos(alpha) + r", ("x", "y", "t"), DEFINITIONS)
    written = compile_expression("(sin(pi*t)*(1 - 8*sqrt(x*x + y*y)**2))*cos(sin(pi*t)*(1 - 8*sqrt(x*x + y*y)**2))"
                                 " + sqrt(x*x + y*y)", ("x", "y", "t"))
    assert np.array_equal(named.evaluate(x=x, y=y, t=t), written.evaluate(x=x, y=y, t=t))
    assert named.variables_used == {"x", "y", "t"}   # through the names
    assert compile_expression("g", ("x", "y", "t"), DEFINITIONS).variables_used == {"t"}


def test_each_name_is_evaluated_once():
    # r is used by h and by the expression: its program is counted once in the cost
    once = compile_expression("h + r", ("x", "y"), DEFINITIONS).operations
    r_ops = compile_expression("sqrt(x*x + y*y)", ("x", "y")).operations
    h_ops = compile_expression("1 - 8*r**2", ("x", "y", "r")).operations
    assert once == compile_expression("h + r", ("x", "y", "h", "r")).operations + r_ops + h_ops


def test_the_length_limit_is_per_text_not_written_out():
    long = "+".join(["x"] * 400)   # 799 characters
    definitions = {"a": long, "b": "a*a*a", "c": "b+b+b"}
    assert len(long) < MAX_LENGTH
    value = compile_expression("c", ("x",), definitions).evaluate(x=1.0)
    assert float(value) == 3 * 400 ** 3


@pytest.mark.parametrize("definitions,message", [
    ({"a": "b + 1", "b": "a * 2"}, "in a cycle: a -> b -> a"),
    ({"a": "a"}, "in a cycle: a -> a"),
    ({"a": "q"}, "in the named expression 'a': unknown name 'q'"),
    ({"a": "1 +"}, "in the named expression 'a': the expression ends where a value is expected"),
    ({f"d{k}": f"d{k + 1}" for k in range(MAX_DEFINITION_CHAIN + 1)} | {f"d{MAX_DEFINITION_CHAIN + 1}": "x"},
     f"nested more than {MAX_DEFINITION_CHAIN} deep"),
])
def test_bad_definitions_are_refused_naming_them(definitions, message):
    with pytest.raises(ExpressionError, match=message.replace("(", r"\(").replace("+", r"\+")):
        compile_expression(next(iter(definitions)), ("x",), definitions)
    assert any(message in text for _, text in definition_problems(definitions, ("x",)))


def test_names_and_count_are_checked():
    assert definition_problems({"x": "1", "pi": "2", "sin": "3", "2a": "4"}, ("x",)) == [
        ("x", "'x' is already a variable of expressions"), ("pi", "'pi' is already a constant of expressions"),
        ("sin", "'sin' is already a function of expressions"),
        ("2a", "a name is letters, digits and _, starting with a letter or _")]
    many = {f"n{k}": "1" for k in range(MAX_DEFINITIONS + 1)}
    assert definition_problems(many, ("x",)) == [("", f"at most {MAX_DEFINITIONS} named expressions, "
                                                      f"got {MAX_DEFINITIONS + 1}")]
    assert definition_problems(dict(list(many.items())[:MAX_DEFINITIONS]), ("x",)) == []


def test_a_name_used_where_its_variables_are_not_allowed_is_refused():
    # a boundary velocity is in t only: a name that reads x is refused there
    with pytest.raises(ExpressionError, match="in the named expression 'r': unknown name 'x'"):
        compile_expression("r", ("t",), DEFINITIONS)


def test_the_scene_takes_named_expressions_and_checks_them():
    scene = json.loads((EXAMPLES / "vortex_2d.json").read_text())
    written = load_scene(scene).body_force
    scene["expressions"] = {"R": "sqrt(X**2 + Y**2)"}
    scene["body_force"] = [text.replace("sqrt(X**2+Y**2)", "R") for text in written]
    assert all(len(a) < len(b) for a, b in zip(scene["body_force"], written))
    loaded = load_scene(scene)
    X, Y, t = np.array([0.8, 1.0, 1.2]), np.array([0.1, -0.3, 0.2]), 0.37
    for named, plain in zip(loaded.body_force, written):
        a = loaded.expression(named, ("X", "Y", "t")).evaluate(X=X, Y=Y, t=t)
        b = compile_expression(plain, ("X", "Y", "t")).evaluate(X=X, Y=Y, t=t)
        assert np.allclose(a, b, rtol=1e-13, atol=0)
    scene["expressions"] = {"R": "Q", "Q": "R"}
    with pytest.raises(SceneError) as caught:
        load_scene(scene)
    assert "expressions.R: the named expressions refer to each other in a cycle: R -> Q -> R" in str(caught.value)
    scene["expressions"] = {"R": "sqrt(X**2 + Y**2)"}
    scene["bodies"][0]["initial_velocity"] = ["R", 0.0]   # an initial velocity is in x, y, z only
    with pytest.raises(SceneError, match=r"bodies\[0\].initial_velocity\[0\]: .*in the named expression 'R'"):
        load_scene(scene)
