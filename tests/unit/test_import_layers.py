"""solver/ (and the service and the SDK) imports in layers: no module imports, at its top or inside a function, a module that
imports it back, however long the way round. The scene's models sit below the registries'
readers (capabilities) and below the checks that count a scene (scene_checks, summary,
stability, seeding); a registry hands its names down instead of being imported from below."""
from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def module_names(package: Path) -> dict[str, Path]:
    names = {}
    for path in package.rglob("*.py"):
        parts = path.relative_to(package.parent).with_suffix("").parts
        names[".".join(parts[:-1] if parts[-1] == "__init__" else parts)] = path
    return names


def imported(module: str, path: Path, known: dict[str, Path]) -> set[str]:
    """The modules of `known` that `module` imports anywhere in its text. A package's own
    `__init__` is not counted as imported by `from package import submodule`."""
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            wanted = [alias.name for alias in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(package.split(".")[: len(package.split(".")) - node.level + 1] + [base]).strip(".")
            wanted = [f"{base}.{a.name}" if f"{base}.{a.name}" in known else base for a in node.names]
        else:
            continue
        for name in wanted:
            while name and name not in known:
                name = name.rpartition(".")[0]
            if name and name != module:
                found.add(name)
    return found


def first_circle(edges: dict[str, set[str]]) -> list[str] | None:
    """A way round (its modules in import order, the first repeated at the end), or None."""
    state: dict[str, str] = {}

    def visit(module: str, trail: list[str]) -> list[str] | None:
        state[module] = "open"
        for target in sorted(edges[module]):
            if state.get(target) == "open":
                return trail[trail.index(target):] + [module, target] if target in trail else [module, target]
            if target not in state and (circle := visit(target, trail + [module])):
                return circle
        state[module] = "done"
        return None

    for module in sorted(edges):
        if module not in state and (circle := visit(module, [])):
            return circle
    return None


def import_edges(package: Path) -> dict[str, set[str]]:
    known = module_names(package)
    return {module: imported(module, path, known) for module, path in known.items()}


@pytest.mark.parametrize("package", ["solver", "service", "clients/python/mpm_client"])
def test_a_package_has_no_import_circle(package):
    circle = first_circle(import_edges(ROOT / package))
    assert circle is None, f"{package}/ imports in a circle: " + " -> ".join(circle)


def test_a_circle_through_a_function_level_import_is_found(tmp_path):
    package = tmp_path / "pkg"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "low.py").write_text("def f():\n    from pkg import high\n")
    (package / "mid.py").write_text("from pkg.low import f\n")
    (package / "high.py").write_text("from . import mid\n")
    assert first_circle(import_edges(package)) == ["pkg.high", "pkg.mid", "pkg.low", "pkg.high"]
