"""The documentation against the code: no doc calls an implemented feature "not supported
yet", docs/cli.md lists exactly the commands `mpm` has and the examples `mpm examples`
lists, the docs point only to files that are in the repository, and each table of
docs/benchmarks.md names the script or test whose output it is."""
from __future__ import annotations

import re
from pathlib import Path

import pytest

from solver import capabilities
from solver.cli import build_parser
from solver.examples import list_examples
from solver.scene import Scene

ROOT = Path(__file__).resolve().parents[2]
DOCS = sorted((ROOT / "docs").glob("*.md")) + [ROOT / "README.md"]
CAPABILITY_SETS = ("FORMULATIONS", "SCHEMES", "TRANSFERS", "GEOMETRIES", "BOUNDARY_CONDITIONS", "WALL_MODES",
                   "MATERIAL_MODELS", "SHAPE_FUNCTIONS", "OUTPUT_FIELDS")
UNSUPPORTED_PHRASES = re.compile(r"not (?:supported|implemented) yet", re.IGNORECASE)
QUOTED = re.compile(r"""['"`]([A-Za-z_][\w+-]*)['"`]""")


def supported_names() -> set[str]:
    return set().union(*(set(getattr(capabilities, name)) for name in CAPABILITY_SETS))


def schema_names() -> set[str]:
    """Every string value the scene's JSON Schema enumerates (the contract's names)."""
    found: set[str] = set()

    def walk(node):
        if isinstance(node, dict):
            found.update(v for v in node.get("enum", []) if isinstance(v, str))
            if isinstance(node.get("const"), str):
                found.add(node["const"])
            for value in node.values():
                walk(value)
        elif isinstance(node, list):
            for value in node:
                walk(value)
    walk(Scene.model_json_schema())
    return found


def paragraphs(path: Path) -> list[str]:
    return [block for block in re.split(r"\n\s*\n", path.read_text(encoding="utf-8")) if block.strip()]


def unsupported_claims() -> list[tuple[str, str]]:
    """(doc, paragraph) of every paragraph that says something is not supported yet."""
    return [(path.name, block) for path in DOCS for block in paragraphs(path) if UNSUPPORTED_PHRASES.search(block)]


@pytest.mark.parametrize("doc, paragraph", unsupported_claims(), ids=lambda value: value[:40])
def test_no_doc_calls_an_implemented_feature_not_supported(doc, paragraph):
    """A paragraph that says "not supported yet" quotes no feature the capability lists have
    (a quoted name of the contract: an enumerated value of the scene's schema, such as a
    material model, a formulation or a wall mode)."""
    named = {name for name in QUOTED.findall(paragraph) if name in schema_names()}
    wrong = named & supported_names()
    assert not wrong, f"{doc} says {sorted(wrong)} are not supported, but solver/capabilities.py lists them:\n{paragraph}"


def test_the_unsupported_example_of_scene_md_is_what_validation_says():
    """docs/scene.md quotes the error of an unsupported feature (too many processes): the
    solver gives it, word for word."""
    from solver.scene import SceneError
    from solver.scene_checks import load_scene
    quoted = re.search(r"`(parallel\.processes): ((\d+) processes is not supported yet \(at most \d+\))`",
                       (ROOT / "docs" / "scene.md").read_text(encoding="utf-8"))
    assert quoted, "docs/scene.md no longer quotes the unsupported-feature error"
    path, message, processes = quoted.groups()
    scene = {"dimension": 2, "grid": {"lower": [0, 0], "upper": [1, 1], "cell_size": 0.1},
             "materials": {"m": {"model": "linear_elastic", "density": 1, "youngs_modulus": 1, "poisson_ratio": 0.3}},
             "bodies": [{"name": "b", "material": "m", "geometry": {"type": "box", "lower": [0.2, 0.2], "upper": [0.4, 0.4]}}],
             "parallel": {"processes": int(processes)},
             "time": {"end": 1.0}}
    with pytest.raises(SceneError) as refused:
        load_scene(scene)
    assert {"path": path, "message": message} in refused.value.errors


def table_first_cells(text: str, header: str) -> list[str]:
    """The first column of the markdown table that starts with `header`, backticks removed."""
    table = text[text.index(header):].split("\n\n", 1)[0]
    return [line.strip("|").split("|")[0].strip().strip("`") for line in table.splitlines()[2:]]


def test_cli_md_lists_every_command_of_mpm():
    text = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
    documented = [cell.removeprefix("mpm ") for cell in table_first_cells(text, "| command | does | from |")]
    parser = build_parser(["--help"])  # loads every package's commands, as `mpm --help` does
    commands = next(action for action in parser._subparsers._group_actions).choices
    assert sorted(documented) == sorted(commands)


def test_cli_md_lists_every_example():
    text = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
    documented = table_first_cells(text, "| example | what it shows |")
    assert sorted(documented) == sorted(example["name"] for example in list_examples())
    assert len(documented) == len(set(documented))


# Paths in backticks that start with one of the repository's folders must exist.
REPOSITORY_PATH = re.compile(r"`((?:solver|service|core|worker|clients|tests|benchmarks|examples|docs|scripts)"
                             r"/[\w./-]*\w)`")


@pytest.mark.parametrize("doc", DOCS, ids=lambda path: path.name)
def test_docs_point_only_to_files_in_the_repository(doc):
    text = doc.read_text(encoding="utf-8")
    assert "../shared" not in text and "shared/design" not in text, f"{doc.name} points outside the repository"
    missing = []
    for target in re.findall(r"\]\(([^)\s]+)\)", text):
        if target.startswith(("http://", "https://", "#", "mailto:")):
            continue
        if not (doc.parent / target.split("#")[0]).exists():
            missing.append(target)
    for path in REPOSITORY_PATH.findall(text):
        # a file or folder, or a module (`solver/runner`) or a name in one (`solver/checkpoint.load`)
        candidates = (path, path + ".py", path.rsplit(".", 1)[0] + ".py")
        if not any((ROOT / candidate).exists() for candidate in candidates):
            missing.append(path)
    assert not missing, f"{doc.name} points to files that are not in the repository: {missing}"


# A script or test that produces a table's figures, named in the table's section.
PRODUCER = re.compile(r"(?<![\w/])((?:benchmarks|tests)/[\w/]+\.py)")


def table_sections(path: Path) -> list[tuple[str, str]]:
    """(heading, text) of each section of `path` (split at its headings) that holds a table."""
    sections = re.split(r"^(#{1,4} .*)$", path.read_text(encoding="utf-8"), flags=re.MULTILINE)
    return [(heading, text) for heading, text in zip(sections[1::2], sections[2::2])
            if re.search(r"^\|.*\|\s*\n\|[-| :]+\|\s*$", text, flags=re.MULTILINE)]


@pytest.mark.parametrize("heading, text", [pytest.param(heading, text, id=heading.lstrip("# ")[:40])
                                           for heading, text in table_sections(ROOT / "docs" / "benchmarks.md")])
def test_every_benchmark_table_names_the_script_that_gives_it(heading, text):
    """docs/benchmarks.md holds the figures that scripts print: a table whose section names no
    script under benchmarks/ or tests/ (that exists) could not be checked or brought up to date."""
    producers = [name for name in PRODUCER.findall(text) if (ROOT / name).is_file()]
    assert producers, f"docs/benchmarks.md {heading!r}: a table without the script or test that gives its figures"
