"""Hypothesis strategies built from the scene's JSON Schema (GET /v1/schema/scene): values of
the declared shapes (objects with their keys, arrays within their lengths, the enums and
consts), with numbers drawn both within their bounds and from the extremes an attacker
sends (1e308, 1e-308, 1e300, 10^30, 2^63). Schemathesis generates from the OpenAPI
document, where a scene is an untyped object: this reaches inside it.

Only what the scene schema uses is supported: $ref to $defs, anyOf / oneOf, const, enum,
object, array, number, integer, string, boolean, null."""
from __future__ import annotations

from typing import Any

from hypothesis import strategies as st

EXTREME_NUMBERS = [0.0, -0.0, 1.0, -1.0, 1e-308, -1e-308, 5e-324, 1e300, -1e300, 1e308, -1e308,
                   1.7976931348623157e308, 1e-9, 1e9]
EXTREME_INTEGERS = [0, 1, -1, 2, 3, 100, 10**6, 10**9, 2**31, 2**53 + 1, 2**63, 10**30, -(10**30)]
MAX_ITEMS = 3      # arrays are drawn short (the body limits and the schema's caps are tested elsewhere)
MAX_DEPTH = 6      # past this depth arrays are drawn at their minimum length (unions of unions...)


def from_schema(node: dict[str, Any], defs: dict[str, Any], depth: int = 0) -> st.SearchStrategy:
    """Values of the JSON Schema `node` (its $refs looked up in `defs`)."""
    if "$ref" in node:
        target = defs[node["$ref"].rsplit("/", 1)[-1]]
        return st.deferred(lambda: from_schema(target, defs, depth + 1))
    if "const" in node:
        return st.just(node["const"])
    if "enum" in node:
        return st.sampled_from(node["enum"])
    for key in ("anyOf", "oneOf", "allOf"):
        if key in node:
            return st.one_of([from_schema(option, defs, depth + 1) for option in node[key]])
    kind = node.get("type")
    if isinstance(kind, list):
        return st.one_of([from_schema({**node, "type": one}, defs, depth) for one in kind])
    make = _BY_TYPE.get(kind)
    return make(node, defs, depth) if make else st.none() | st.booleans() | st.integers() | st.text(max_size=8)


def _object(node: dict[str, Any], defs: dict[str, Any], depth: int) -> st.SearchStrategy:
    properties = node.get("properties", {})
    required = set(node.get("required", []))
    fixed = {key: from_schema(value, defs, depth + 1) for key, value in properties.items() if key in required}
    optional = {key: from_schema(value, defs, depth + 1) for key, value in properties.items() if key not in required}
    extra = node.get("additionalProperties")
    if not properties and isinstance(extra, dict):   # a map (materials: name -> material)
        return st.dictionaries(st.text(min_size=1, max_size=6), from_schema(extra, defs, depth + 1),
                               min_size=node.get("minProperties", 0), max_size=2)
    return st.fixed_dictionaries(fixed, optional=optional)


def _array(node: dict[str, Any], defs: dict[str, Any], depth: int) -> st.SearchStrategy:
    low = node.get("minItems", 0)
    high = low if depth > MAX_DEPTH else min(node.get("maxItems", low + MAX_ITEMS), low + MAX_ITEMS)
    return st.lists(from_schema(node.get("items", {}), defs, depth + 1), min_size=low, max_size=high)


def _number(node: dict[str, Any], defs: dict[str, Any], depth: int) -> st.SearchStrategy:
    low = node.get("minimum", node.get("exclusiveMinimum"))
    high = node.get("maximum", node.get("exclusiveMaximum"))
    inside = st.floats(min_value=low, max_value=high, allow_nan=False, allow_infinity=False,
                       exclude_min="exclusiveMinimum" in node, exclude_max="exclusiveMaximum" in node)
    return inside | st.sampled_from(EXTREME_NUMBERS)


def _integer(node: dict[str, Any], defs: dict[str, Any], depth: int) -> st.SearchStrategy:
    low = node.get("minimum", node.get("exclusiveMinimum", -(10**6)))
    high = node.get("maximum", node.get("exclusiveMaximum", 10**6))
    return st.integers(min_value=low, max_value=high) | st.sampled_from(EXTREME_INTEGERS)


def _string(node: dict[str, Any], defs: dict[str, Any], depth: int) -> st.SearchStrategy:
    return st.text(max_size=12) | st.sampled_from(["", "x", "0.1*t", "sin(x)", "x.__class__", "\r\n", "../../etc"])


_BY_TYPE = {"object": _object, "array": _array, "number": _number, "integer": _integer, "string": _string,
            "boolean": lambda node, defs, depth: st.booleans(), "null": lambda node, defs, depth: st.none()}


def scenes(schema: dict[str, Any]) -> st.SearchStrategy:
    """Whole scenes of the schema's shape (mostly refused for their cross rules: dimensions,
    names, a body outside the grid)."""
    return from_schema(schema, schema.get("$defs", {}))


def scene_parts(schema: dict[str, Any]) -> st.SearchStrategy:
    """(key, value) of one top-level key of a scene, the value of the schema's shape for it:
    put into a valid scene, it reaches the deeper rules (limits, counting, the summary)."""
    defs = schema.get("$defs", {})
    keys = sorted(schema["properties"])
    return st.sampled_from(keys).flatmap(
        lambda key: st.tuples(st.just(key), from_schema(schema["properties"][key], defs)))
