"""The whitelist expression parser: results against numpy, broadcasting, rejections."""

import numpy as np
import pytest

from solver.expressions import MAX_DEPTH, MAX_LENGTH, ExpressionError, compile_expression

XYZ = ("x", "y", "z")
x = np.linspace(-2.0, 3.0, 11)
y = np.linspace(0.5, 4.0, 11)


def evaluate(text, variables=XYZ, **values):
    return compile_expression(text, variables).evaluate(**values)


def test_matches_numpy_on_arrays():
    got = evaluate("0.1*sin(2*pi*x) + y**2/3 - exp(-x*y) + sqrt(abs(x))*cos(y)", x=x, y=y)
    expected = 0.1 * np.sin(2 * np.pi * x) + y**2 / 3 - np.exp(-x * y) + np.sqrt(np.abs(x)) * np.cos(y)
    np.testing.assert_allclose(got, expected, rtol=1e-15, atol=1e-15)


@pytest.mark.parametrize("text, expected", [
    ("-2**2", -4.0),        # ** binds tighter than unary minus, as in Python
    ("2**3**2", 512.0),     # ** is right-associative
    ("1-2-3", -4.0),        # - is left-associative
    ("8/4/2", 1.0),
    ("2+3*4", 14.0),
    ("(2+3)*4", 20.0),
    ("--3", 3.0),
    ("+3", 3.0),
    ("1.5e3 + .5 + 2.", 1502.5),
    ("pi", np.pi),
    ("e", np.e),
])
def test_arithmetic_and_precedence(text, expected):
    assert evaluate(text) == pytest.approx(expected, rel=1e-15)


@pytest.mark.parametrize("text, reference", [
    ("sin(x)", np.sin), ("cos(x)", np.cos), ("tan(x)", np.tan), ("exp(x)", np.exp),
    ("log(y)", lambda _: np.log(y)), ("sqrt(y)", lambda _: np.sqrt(y)),
    ("abs(x)", np.abs), ("sign(x)", np.sign),
    ("min(x, 1)", lambda v: np.minimum(v, 1)), ("max(x, 1)", lambda v: np.maximum(v, 1)),
    ("min(x, y, 0.5)", lambda v: np.minimum(np.minimum(v, y), 0.5)),
    ("max(x, y, 0.5)", lambda v: np.maximum(np.maximum(v, y), 0.5)),
    ("where(x < 0, -1, 2)", lambda v: np.where(v < 0, -1.0, 2.0)),
    ("sinh(x)", np.sinh), ("cosh(x)", np.cosh), ("tanh(x)", np.tanh), ("atan(x)", np.arctan),
    ("asin(x / 10)", lambda v: np.arcsin(v / 10)), ("acos(x / 10)", lambda v: np.arccos(v / 10)),
    ("atan2(y, x)", lambda v: np.arctan2(y, v)),
])
def test_every_function(text, reference):
    np.testing.assert_array_equal(evaluate(text, x=x, y=y), reference(x))


@pytest.mark.parametrize("operator, ufunc", [
    ("<", np.less), ("<=", np.less_equal), (">", np.greater),
    (">=", np.greater_equal), ("==", np.equal), ("!=", np.not_equal),
])
def test_comparisons_inside_where(operator, ufunc):
    values = np.array([-1.0, 0.0, 1.0])
    got = evaluate(f"where(x {operator} 0, x + 10, x - 10)", x=values)
    np.testing.assert_array_equal(got, np.where(ufunc(values, 0), values + 10, values - 10))


def test_nested_where_combines_conditions():
    got = evaluate("where(x > 0, where(x < 2, 1, 0), 0)", x=x)
    np.testing.assert_array_equal(got, ((x > 0) & (x < 2)).astype(float))


def test_scalars_broadcast_against_arrays():
    got = evaluate("x * t", ("x", "t"), x=x, t=2.0)
    np.testing.assert_array_equal(got, 2.0 * x)
    assert got.dtype == np.float64


def test_result_has_the_shape_of_all_given_values():
    # A constant, or an expression in t only, still gives one value per particle.
    constant = evaluate("0.25", x=x, y=y)
    assert constant.shape == x.shape and np.all(constant == 0.25)
    in_time = compile_expression("1 - exp(-t)", ("x", "t")).evaluate(x=x, t=1.0)
    np.testing.assert_allclose(in_time, np.full(x.shape, 1 - np.exp(-1.0)), rtol=1e-15)


def test_scalar_inputs_give_a_scalar_array():
    got = evaluate("x + y", x=1.0, y=2.0)
    assert got.shape == () and got == 3.0


def test_result_is_a_new_writable_array():
    values = np.ones(3)
    got = evaluate("x", x=values)
    got[0] = 5.0
    assert values[0] == 1.0


def test_variables_used():
    assert compile_expression("x*y + t + pi", ("x", "y", "z", "t")).variables_used == {"x", "y", "t"}
    assert compile_expression("2", XYZ).variables_used == frozenset()


def test_missing_value_at_evaluation():
    with pytest.raises(ExpressionError, match="no value given for y"):
        compile_expression("x + y", XYZ).evaluate(x=x)


@pytest.mark.parametrize("text, message", [
    ("import os", "unknown name 'import' at column 1"),
    ("open('f')", "function 'open' is not allowed at column 1"),
    ("__import__('os')", "function '__import__' is not allowed"),
    ("eval(x)", "function 'eval' is not allowed"),
    ("x.__class__", "unexpected character '.' at column 2"),
    ("().__class__", "attribute access is not allowed"),
    ("lambda x: x", "unknown name 'lambda'"),
    ("[x for x in y]", "unexpected character '['"),
    ("'abc'", "strings are not allowed"),
    ('"abc"', "strings are not allowed"),
    ("q + 1", "unknown name 'q' at column 1"),
    ("x + t", "unknown name 't' at column 5"),
    ("x ^ 2", "use '**' for powers"),
    ("x = 1", "assignment is not allowed"),
    ("x @ y", "unexpected character '@'"),
    ("sin x", "needs its arguments in parentheses"),
    ("sin(x, y)", "takes 1 argument(s), got 2"),
    ("min(x)", "takes at least 2 argument(s), got 1"),
    ("where(x, 1, 2)", "must be a comparison"),
    ("where(x < 0, 1)", "takes 3 argument(s), got 2"),
    ("x < 1", "can only be the condition of where()"),
    ("where(x < 0, y < 1, 2)", "can only be the condition of where()"),
    ("1 + (x < 0)", "can only be the condition of where()"),
    ("where(0 < x < 1, 1, 2)", "chained comparison"),
    ("(x + 1", "expected ')'"),
    ("x + 1)", "unexpected ')' at column 6"),
    ("x +", "ends where a value is expected"),
    ("2 3", "unexpected '3' at column 3"),
    ("", "empty"),
    ("1e999", "out of range"),
])
def test_rejected(text, message):
    with pytest.raises(ExpressionError) as caught:
        compile_expression(text, XYZ)
    assert message in str(caught.value)


def test_too_long():
    text = "+".join(["x"] * (MAX_LENGTH // 2 + 1))
    assert len(text) > MAX_LENGTH
    with pytest.raises(ExpressionError, match="longer than"):
        compile_expression(text, XYZ)


def test_long_flat_sum_within_the_limit_evaluates():
    # 500 terms: the postfix program is evaluated without recursion.
    text = "+".join(["x"] * (MAX_LENGTH // 2))
    assert evaluate(text, x=1.0) == MAX_LENGTH // 2


@pytest.mark.parametrize("text", [
    "(" * (MAX_DEPTH + 1) + "x" + ")" * (MAX_DEPTH + 1),
    "-" * (MAX_DEPTH + 1) + "x",
    "**".join(["2"] * (MAX_DEPTH + 2)),
    "sin(" * (MAX_DEPTH + 1) + "x" + ")" * (MAX_DEPTH + 1),
])
def test_too_deep(text):
    with pytest.raises(ExpressionError, match="nested too deeply"):
        compile_expression(text, XYZ)


def test_nesting_just_within_the_limit_is_accepted():
    depth = MAX_DEPTH - 1
    assert evaluate("(" * depth + "x" + ")" * depth, x=2.0) == 2.0


def test_not_a_string():
    with pytest.raises(ExpressionError, match="must be a string"):
        compile_expression(3, XYZ)


def test_inverse_and_hyperbolic_identities():
    """cosh^2 - sinh^2 = 1, tanh = sinh / cosh, atan2 gives the quadrant that atan cannot."""
    t = np.linspace(-3.0, 3.0, 13)
    np.testing.assert_allclose(evaluate("cosh(t)**2 - sinh(t)**2", ("t",), t=t), 1.0, rtol=0, atol=1e-12)
    np.testing.assert_allclose(evaluate("tanh(t) - sinh(t) / cosh(t)", ("t",), t=t), 0.0, atol=1e-15)
    assert evaluate("atan2(1, -1)") == pytest.approx(3 * np.pi / 4)
    assert evaluate("atan(1 / -1)") == pytest.approx(-np.pi / 4)


def test_atan2_takes_two_arguments():
    with pytest.raises(ExpressionError, match="atan2"):
        compile_expression("atan2(x)", ("x",))
