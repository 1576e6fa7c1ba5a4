"""Safe arithmetic expressions for scene fields (initial velocities, prescribed
velocities, body forces).

The text is read by a small tokenizer and a recursive-descent parser; nothing the
user writes is ever given to ``eval``/``exec``/``compile``. The parser emits a
postfix program of numpy operations once; ``Expression.evaluate`` runs it with a
value stack (no recursion), vectorised over whatever arrays it is given.

Grammar (``**`` binds tighter than unary minus and is right-associative, as in
Python, so ``-2**2 == -4``)::

    expression := sum [comparison-operator sum]      (comparison: only as the condition of where)
    sum        := product (("+" | "-") product)*
    product    := unary (("*" | "/") unary)*
    unary      := ("-" | "+") unary | power
    power      := atom ["**" unary]
    atom       := number | constant | variable | function "(" expression ("," expression)* ")"
                | "(" expression ")"
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass

import numpy as np

from solver.errors import SolverError

MAX_LENGTH = 1000
MAX_DEPTH = 50
# Named sub-expressions (a scene's `expressions`): how many, and how long a chain of
# names may refer one to the next. Each one is at most MAX_LENGTH characters and is
# evaluated once per evaluation of the expression that uses it, so these two bound the
# work an evaluation can cost (the names are not written out into one long text).
MAX_DEFINITIONS = 200
MAX_DEFINITION_CHAIN = 32
_NAME = re.compile(r"^[A-Za-z_][A-Za-z_0-9]*$")

CONSTANTS = {"pi": math.pi, "e": math.e}

# Functions of one argument, by name.
_UNARY = {
    "sin": np.sin, "cos": np.cos, "tan": np.tan, "asin": np.arcsin, "acos": np.arccos, "atan": np.arctan,
    "sinh": np.sinh, "cosh": np.cosh, "tanh": np.tanh, "exp": np.exp, "log": np.log, "sqrt": np.sqrt,
    "abs": np.abs, "sign": np.sign,
}
# name -> (numpy function, minimum number of arguments, maximum or None for any)
FUNCTIONS: dict[str, tuple[Callable[..., np.ndarray], int, int | None]] = {
    **{name: (function, 1, 1) for name, function in _UNARY.items()},
    "atan2": (np.arctan2, 2, 2),   # atan2(y, x): the angle of (x, y), in (-pi, pi]
    "min": (lambda *a: _reduce(np.minimum, a), 2, None),
    "max": (lambda *a: _reduce(np.maximum, a), 2, None),
    "where": (np.where, 3, 3),
}

_BINARY = {"+": np.add, "-": np.subtract, "*": np.multiply, "/": np.divide, "**": np.power}
_COMPARISONS = {
    "<": np.less, "<=": np.less_equal, ">": np.greater,
    ">=": np.greater_equal, "==": np.equal, "!=": np.not_equal,
}

_TOKEN = re.compile(
    r"(?P<space>\s+)"
    r"|(?P<number>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)"
    r"|(?P<name>[A-Za-z_][A-Za-z_0-9]*)"
    r"|(?P<op>\*\*|<=|>=|==|!=|[-+*/()<>,])"
)
# Characters that people try from Python or other languages, with a hint.
_HINTS = {
    "^": "use '**' for powers",
    "'": "strings are not allowed",
    '"': "strings are not allowed",
    ".": "attribute access is not allowed",
    "[": "indexing and lists are not allowed",
    "=": "assignment is not allowed; use '==' inside where()",
    "&": "use nested where() instead of logical operators",
    "|": "use nested where() instead of logical operators",
}


def _reduce(ufunc: np.ufunc, args: tuple) -> np.ndarray:
    result = args[0]
    for arg in args[1:]:
        result = ufunc(result, arg)
    return result


class ExpressionError(SolverError, ValueError):
    """The text is not a valid expression; the message names the token and column."""


@dataclass(frozen=True)
class _Token:
    kind: str  # "number" | "name" | "op" | "end"
    text: str
    column: int  # 1-based


def _next_token(text: str, position: int) -> tuple[_Token, int]:
    """The token starting at or after ``position`` (skipping blanks) and the position after it."""
    match = _TOKEN.match(text, position)
    if match is not None and match.lastgroup == "space":
        position = match.end()
        match = _TOKEN.match(text, position)
    if position >= len(text):
        return _Token("end", "", len(text) + 1), position
    if match is None:
        char = text[position]
        hint = _HINTS.get(char)
        message = f"unexpected character {char!r} at column {position + 1}"
        raise ExpressionError(f"{message} ({hint})" if hint else message)
    return _Token(match.lastgroup, match.group(), position + 1), match.end()


# One instruction of the postfix program: ("const", value, 0), ("var", name, 0)
# or ("call", numpy function, number of arguments taken from the stack).
_Instruction = tuple[str, object, int]


class _Parser:
    """Recursive descent over the tokens, emitting postfix instructions.

    Each parse method returns the kind of value it produced: "number" or
    "condition" (the result of a comparison, only valid as where's first argument).
    """

    def __init__(self, text: str, variables: frozenset[str]):
        # Tokens are read one ahead, on demand, so that errors come in reading order.
        self.text = text
        self.token, self.position = _next_token(text, 0)
        self.variables = variables
        self.used: set[str] = set()
        self.program: list[_Instruction] = []
        self.depth = 0

    def _advance(self) -> _Token:
        token = self.token
        self.token, self.position = _next_token(self.text, self.position)
        return token

    def _expect(self, text: str) -> None:
        if self.token.text != text:
            raise ExpressionError(f"expected {text!r} {self._found()}")
        self._advance()

    def _found(self) -> str:
        if self.token.kind == "end":
            return "at the end of the expression"
        return f"but found {self.token.text!r} at column {self.token.column}"

    def parse(self) -> None:
        if self.token.kind == "end":
            raise ExpressionError("the expression is empty")
        start = self.token
        if self._expression() == "condition":
            raise _condition_misplaced(start)
        if self.token.kind != "end":
            raise ExpressionError(f"unexpected {self.token.text!r} at column {self.token.column}")

    def _expression(self) -> str:
        start = self.token
        kind = self._sum()
        if self.token.text in _COMPARISONS:
            operator = self._advance()
            if kind == "condition":
                raise _condition_misplaced(start)
            if self._sum() == "condition" or self.token.text in _COMPARISONS:
                raise ExpressionError(
                    f"chained comparison after {operator.text!r} at column {operator.column}; "
                    "nest where() instead"
                )
            self._emit(_COMPARISONS[operator.text], 2, operator)
            return "condition"
        return kind

    def _sum(self) -> str:
        return self._left_associative(("+", "-"), self._product)

    def _product(self) -> str:
        return self._left_associative(("*", "/"), self._unary)

    def _left_associative(self, operators: tuple[str, ...], operand: Callable[[], str]) -> str:
        """operand (operator operand)*, every operand a number (not a condition)."""
        start = self.token
        kind = operand()
        while self.token.text in operators:
            operator = self._advance()
            right_start = self.token
            self._number(kind, start)
            self._number(operand(), right_start)
            self._emit(_BINARY[operator.text], 2, operator)
        return kind

    def _unary(self) -> str:
        # Every recursive path of the grammar passes here, so the depth is counted here.
        self.depth += 1
        if self.depth > MAX_DEPTH:
            raise ExpressionError(
                f"the expression is nested too deeply (more than {MAX_DEPTH} levels) "
                f"at column {self.token.column}"
            )
        if self.token.text in ("-", "+"):
            operator = self._advance()
            start = self.token
            self._number(self._unary(), start)
            if operator.text == "-":
                self._emit(np.negative, 1, operator)
            kind = "number"
        else:
            kind = self._power()
        self.depth -= 1
        return kind

    def _power(self) -> str:
        start = self.token
        kind = self._atom()
        if self.token.text == "**":
            operator = self._advance()
            right_start = self.token
            self._number(kind, start)
            self._number(self._unary(), right_start)
            self._emit(np.power, 2, operator)
        return kind

    def _atom(self) -> str:
        token = self._advance()
        if token.kind == "number":
            value = float(token.text)
            if not math.isfinite(value):
                raise ExpressionError(f"number {token.text!r} at column {token.column} is out of range")
            self.program.append(("const", value, 0))
            return "number"
        if token.kind == "name":
            if self.token.text == "(":
                return self._call(token)
            if token.text in self.variables:
                self.used.add(token.text)
                self.program.append(("var", token.text, 0))
                return "number"
            if token.text in CONSTANTS:
                self.program.append(("const", CONSTANTS[token.text], 0))
                return "number"
            if token.text in FUNCTIONS:
                raise ExpressionError(
                    f"function {token.text!r} at column {token.column} needs its arguments in parentheses"
                )
            allowed = ", ".join(sorted(self.variables)) or "none"
            raise ExpressionError(
                f"unknown name {token.text!r} at column {token.column} (allowed variables: {allowed})"
            )
        if token.text == "(":
            kind = self._expression()
            self._expect(")")
            return kind
        if token.kind == "end":
            raise ExpressionError("the expression ends where a value is expected")
        raise ExpressionError(f"unexpected {token.text!r} at column {token.column}")

    def _call(self, name: _Token) -> str:
        if name.text not in FUNCTIONS:
            allowed = ", ".join(sorted(FUNCTIONS))
            raise ExpressionError(
                f"function {name.text!r} is not allowed at column {name.column} (allowed: {allowed})"
            )
        function, least, most = FUNCTIONS[name.text]
        self._expect("(")
        kinds: list[tuple[str, _Token]] = []
        while True:
            start = self.token
            kinds.append((self._expression(), start))
            if self.token.text != ",":
                break
            self._advance()
        self._expect(")")
        count = len(kinds)
        if count < least or (most is not None and count > most):
            wanted = str(least) if most == least else f"at least {least}"
            raise ExpressionError(
                f"function {name.text!r} at column {name.column} takes {wanted} argument(s), got {count}"
            )
        for position, (kind, start) in enumerate(kinds):
            if name.text == "where" and position == 0:
                if kind != "condition":
                    raise ExpressionError(
                        f"the first argument of where() at column {name.column} must be a comparison, "
                        "e.g. where(x < 0, 1, 2)"
                    )
            else:
                self._number(kind, start)
        self._emit(function, count, name)
        return "number"

    def _emit(self, function: Callable[..., np.ndarray], count: int, token: _Token) -> None:
        """Append a call; on constant arguments compute it now instead, so that a constant
        that overflows or divides by zero (``9**9**9``, ``1/0``) is an error here, not an
        infinity in the simulation."""
        arguments = self.program[len(self.program) - count:]
        if any(kind != "const" for kind, _, _ in arguments):
            self.program.append(("call", function, count))
            return
        with np.errstate(all="ignore"):
            value = float(function(*(payload for _, payload, _ in arguments)))
        if not math.isfinite(value):
            raise ExpressionError(
                f"{token.text!r} at column {token.column} gives {value} on constants "
                "(overflow, division by zero or outside the domain)"
            )
        del self.program[len(self.program) - count:]
        self.program.append(("const", value, 0))

    @staticmethod
    def _number(kind: str, start: _Token) -> None:
        if kind == "condition":
            raise _condition_misplaced(start)


def _condition_misplaced(start: _Token) -> ExpressionError:
    return ExpressionError(
        f"the comparison starting at column {start.column} can only be the condition of where()"
    )


class Expression:
    """A compiled expression. ``evaluate(**values)`` returns float64 values."""

    def __init__(self, text: str, program: list[_Instruction], variables_used: frozenset[str],
                 definitions: tuple[tuple[str, "Expression"], ...] = ()):
        self.text = text
        self._program = program
        self.variables_used = variables_used    # the plain variables, through the named expressions too
        # the named expressions it needs, each after those it needs: evaluated once, in order
        self._definitions = definitions

    def evaluate(self, **values: float | np.ndarray) -> np.ndarray:
        """Evaluate element-wise. Every value given (used or not) takes part in the
        broadcast, so ``compile_expression("1", "xy").evaluate(x=xs, y=ys)`` has the
        shape of ``xs``; the result is a new float64 array. Non-finite results
        (e.g. ``1/x`` at x = 0) are returned as they are, for the caller to check."""
        missing = self.variables_used - values.keys()
        if missing:
            raise ExpressionError(f"no value given for {', '.join(sorted(missing))} in {self.text!r}")
        arrays = {name: np.asarray(value, dtype=np.float64) for name, value in values.items()}
        shape = np.broadcast_shapes(*(a.shape for a in arrays.values()))
        with np.errstate(all="ignore"):
            for name, definition in self._definitions:
                arrays[name] = definition._run(arrays)
            result = self._run(arrays)
        return np.array(np.broadcast_to(result, shape), dtype=np.float64)

    def _run(self, arrays: dict) -> np.ndarray | float:
        stack: list = []
        for kind, payload, count in self._program:
            if kind == "const":
                stack.append(payload)
            elif kind == "var":
                stack.append(arrays[payload])
            else:
                arguments = stack[len(stack) - count:]
                del stack[len(stack) - count:]
                stack.append(payload(*arguments))
        (result,) = stack
        return result

    @property
    def operations(self) -> int:
        """Instructions of the program (constants, variables, operations), the named expressions'
        included: what one evaluation costs per value, for the run-time estimate (solver/cost.py)."""
        return len(self._program) + sum(len(d._program) for _, d in self._definitions)

    def __repr__(self) -> str:
        return f"Expression({self.text!r})"


def compile_expression(text: str, variables: Iterable[str],
                       definitions: Mapping[str, str] | None = None) -> Expression:
    """Parse ``text`` allowing only the given variable names and the names of ``definitions``
    (named sub-expressions over the same variables, which may use each other without a
    cycle); raise ExpressionError."""
    if not isinstance(text, str):
        raise ExpressionError("an expression must be a string")
    if len(text) > MAX_LENGTH:
        raise ExpressionError(f"the expression is longer than {MAX_LENGTH} characters")
    allowed = frozenset(variables)
    clashes = allowed & (CONSTANTS.keys() | FUNCTIONS.keys())
    if clashes:
        raise ValueError(f"variable names clash with built-in names: {sorted(clashes)}")
    if not definitions:
        return _parse(text, allowed)
    names = frozenset(definitions) - allowed
    expression = _parse(text, allowed | names)
    order: dict[str, Expression] = {}
    for name in sorted(expression.variables_used & names):
        _resolve(name, definitions, allowed, names, order, ())
    used = (expression.variables_used - names).union(*(d.variables_used for d in order.values()))
    return Expression(text, expression._program, frozenset(used), tuple(order.items()))


def _parse(text: str, allowed: frozenset[str]) -> Expression:
    parser = _Parser(text, allowed)
    parser.parse()
    return Expression(text, parser.program, frozenset(parser.used))


def _resolve(name: str, definitions: Mapping[str, str], allowed: frozenset[str], names: frozenset[str],
             order: dict[str, Expression], chain: tuple[str, ...]) -> None:
    """Compile the named expression ``name`` after those it uses (depth first), into ``order``;
    its program reads the names it uses as variables, evaluated before it."""
    if name in order:
        return
    if name in chain:
        cycle = " -> ".join(chain[chain.index(name):] + (name,))
        raise ExpressionError(f"the named expressions refer to each other in a cycle: {cycle}")
    if len(chain) >= MAX_DEFINITION_CHAIN:
        raise ExpressionError(f"named expressions nested more than {MAX_DEFINITION_CHAIN} deep: "
                              f"{' -> '.join(chain[:3])} -> ... -> {name}")
    text = definitions[name]
    try:
        if not isinstance(text, str):
            raise ExpressionError("an expression must be a string")
        if len(text) > MAX_LENGTH:
            raise ExpressionError(f"the expression is longer than {MAX_LENGTH} characters")
        expression = _parse(text, allowed | names)
    except ExpressionError as exc:
        raise ExpressionError(f"in the named expression {name!r}: {exc}") from None
    for used in sorted(expression.variables_used & names):
        _resolve(used, definitions, allowed, names, order, chain + (name,))
    plain = (expression.variables_used - names).union(*(order[u].variables_used
                                                        for u in expression.variables_used & names))
    order[name] = Expression(text, expression._program, frozenset(plain))


def definition_problems(definitions: Mapping[str, str], variables: Iterable[str]) -> list[tuple[str, str]]:
    """Every problem of a map of named expressions, as (name, message): too many, a name that
    is not an identifier or that is already a variable, constant or function, a text that
    does not compile over ``variables`` and the other names, a cycle, a chain too deep."""
    if len(definitions) > MAX_DEFINITIONS:
        return [("", f"at most {MAX_DEFINITIONS} named expressions, got {len(definitions)}")]
    allowed = frozenset(variables)
    problems = []
    for name in definitions:
        if not _NAME.match(name):
            problems.append((name, "a name is letters, digits and _, starting with a letter or _"))
        elif name in allowed or name in CONSTANTS or name in FUNCTIONS:
            kind = "variable" if name in allowed else "constant" if name in CONSTANTS else "function"
            problems.append((name, f"{name!r} is already a {kind} of expressions"))
    if problems:
        return problems
    names = frozenset(definitions)
    order: dict[str, Expression] = {}
    for name in definitions:
        try:
            _resolve(name, definitions, allowed, names, order, ())
        except ExpressionError as exc:
            problems.append((name, str(exc)))
            break   # one failure leaves `order` part-filled: the others would repeat it
    return problems
