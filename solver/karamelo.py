"""Translate a Karamelo input file (LAMMPS-style commands) into a scene: `mpm import karamelo`.

A Karamelo file is a list of variable definitions (`E = 1e+3`, `hL = 0.5*L`) and
commands (`region(rBall1, cylinder, -hL+R, -hL+R, R)`). Expressions are read by the
scene's own expression parser (solver/expressions.py, a whitelist, never eval): a
Karamelo expression is first rewritten token by token into the scene's syntax (`^` is
`**`, `PI` is `pi`, `time` is `t`, a variable is its value or, when it depends on x, y,
z or time, its parenthesised definition), then compiled; with no variable left it is
evaluated to a number.

A variable that depends on x, y, z or time is kept by its name: the scene's
`expressions` hold it (and the variables it uses), so a body force written with ten
variables stays as short as Karamelo's file; only those a translated field uses are kept.

What a command means is translated only where the scene has the same thing. Every line
is translated, noted (`Translation.notes`: translated, with what differs from Karamelo
stated: a tip force spread over the particles near its nodes, an end time estimated from
a number of adaptive steps), listed (`Translation.untranslated`: not translated, with the
reason) or stops the import (KarameloError naming the line: old syntax, an unreadable
line); nothing is guessed: a missing value stays missing and the scene's validation says
so. The commands and their Karamelo semantics are those of Karamelo's paper ([K] 3.4,
Appendix A), its example files (tests/data/karamelo/) and its sources at commit 08e444d.
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

from solver.errors import SolverError
from solver.expressions import CONSTANTS, FUNCTIONS, MAX_LENGTH, ExpressionError, compile_expression

SCENE_VARIABLES = ("x", "y", "z", "X", "Y", "Z", "t")
# Karamelo's built-in names in the scene's terms: x0, y0, z0 are the reference position
_BUILTINS = {"PI": "pi", "time": "t", "x0": "X", "y0": "Y", "z0": "Z"}
# scene names a Karamelo variable may not take (it gets a suffix): variables, constants, functions
_RESERVED = set(SCENE_VARIABLES) | set(CONSTANTS) | set(FUNCTIONS)
_SCENE_NAME = re.compile(r"(?<![\w.])[A-Za-z_]\w*")
KARAMELO_VERSION = "08e444d"      # the commit of tests/data/karamelo/ (its README)
DEFAULT_DT_FACTOR = 0.9           # Karamelo's dt_factor when the file sets none
MAX_FRAMES = 1001                 # frames from a dump every few steps: more is a file, not a movie
LATE_SHARE = 0.01                 # the runs before a command, as a share of all: a set-up run
_TOKEN = re.compile(r"\s+|(?P<number>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)|(?P<name>[A-Za-z_]\w*)|(?P<op>[-+*/^(),])")
_ASSIGNMENT = re.compile(r"^\s*([A-Za-z_]\w*)\s*=(?!=)\s*(.*)$")
_COMMAND = re.compile(r"^\s*([A-Za-z_]\w*)\s*\((.*)\)\s*$")
# Karamelo functions whose value is computed during a run: no scene equivalent.
_RUNTIME_FUNCTIONS = {"xcm": "a group's centre of mass", "value": "a value frozen during the run"}
_SHAPES = {"linear": "linear", "cubic-spline": "cubic_bspline", "quadratic-spline": "quadratic_bspline",
           "bernstein-quadratic": "bernstein"}
_TRANSFERS = {"flip": "flip", "pic": "pic", "apic": "apic"}
# half the support of each shape function, in cells: how far a particle reaches its nodes
_SUPPORT = {"linear": 1.0, "cubic_bspline": 2.0, "quadratic_bspline": 1.5, "bernstein": 2.0}
_DUMP_FIELDS = {"x": "position", "y": "position", "z": "position", "vx": "velocity", "vy": "velocity",
                "vz": "velocity", "s11": "stress", "s22": "stress", "s33": "stress", "s12": "stress",
                "s13": "stress", "s23": "stress", "seq": "von_mises", "volume": "volume", "mass": "mass",
                "damage": "damage", "T": "temperature", "ienergy": "strain_energy_density",
                "x0": "reference_position", "y0": "reference_position", "z0": "reference_position"}
_OUTPUT_ONLY = ("set_output", "log", "log_modify", "plot", "save_plot")
# commands translated after a first run (a set-up run, LATE_SHARE): they act on nodes or define names
_AFTER_RUN = {"fix", "region", "group", "dump", "run", "run_time"}
INF = float("inf")


class KarameloError(SolverError, ValueError):
    """A file that cannot be imported: a line that cannot be read, or old syntax that Karamelo
    itself no longer reads. Names the line."""


@dataclass
class Untranslated:
    line: int
    text: str
    reason: str


@dataclass
class Translation:
    scene: dict
    untranslated: list[Untranslated] = field(default_factory=list)   # left out, with the reason
    notes: list[Untranslated] = field(default_factory=list)          # translated; what differs, stated


class _Skip(Exception):
    """The current line (or part of it) has no translation: the reason."""


@dataclass
class _Value:
    text: str                  # in the scene's expression syntax (a variable in x, y, z, t: its scene name)
    number: float | None       # when it depends on nothing
    runtime: str | None = None   # why the scene cannot have it (computed during a Karamelo run, too long)


def translate_file(path: str | Path) -> Translation:
    path = Path(path)
    return translate(path.read_text(encoding="utf-8"), name=path.stem)


def translate(text: str, name: str = "karamelo") -> Translation:
    translator = _Translator(name)
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        if line:
            translator.read(number, line)
    return translator.finish()


class _Translator:
    def __init__(self, name: str):
        self.name = name
        self.variables: dict[str, _Value] = {}
        self.untranslated: list[Untranslated] = []
        self.notes: list[Untranslated] = []
        self.definitions: dict[str, str] = {}   # scene name -> text: the variables in x, y, z, t
        self.dimension: int | None = None
        self.method: dict = {"scheme": "musl"}   # Karamelo's default scheme is MUSL ([K] 3.7, Remark 2)
        self.grid: dict = {}
        self.regions: dict[str, dict] = {}
        self.parts: dict[str, dict[str, tuple[int, list]]] = {"eos": {}, "strength": {}, "damage": {}}
        self.materials: dict[str, dict] = {}
        self.speeds: dict[str, float] = {}   # material -> Karamelo's wave speed sqrt((K + 4/3 G) / rho)
        self.bodies: dict[str, dict] = {}
        self.groups: dict[str, tuple[str, str, str | None]] = {}
        self.conditions: list[dict] = []
        self.loads: list[dict] = []
        self.scene: dict = {"time": {}, "output": {}}
        self.dt_factor: tuple[int, float] | None = None
        self.dumps: list[tuple[int, int]] = []          # (line, steps between dumps)
        self.runs: list[tuple[int, str, float]] = []    # (line, "steps" | "time", how many)
        self.late: list[tuple[int, list, dict]] = []    # after a run: (line, the list, what was added)
        self.lines: dict[int, str] = {}
        self.outputs: dict[str, str] = {}   # fix and compute ids: their values exist during a run only
        self.line = 0
        self.initial: float | None = None   # the first time step (fixed, or the adaptive one's first)

    # -- lines ---------------------------------------------------------------

    def read(self, number: int, line: str) -> None:
        self.line = number
        self.lines[number] = line
        try:
            assignment = _ASSIGNMENT.match(line)
            if assignment:
                self.assign(assignment.group(1), assignment.group(2))
                return
            command = _COMMAND.match(line)
            if not command:
                raise KarameloError(f"line {number}: neither a variable definition (name = expression) "
                                    f"nor a command (name(arguments)): {line!r}")
            name, arguments = command.group(1), _split(command.group(2))
            handler = getattr(self, f"cmd_{name}", None)
            if name in _OUTPUT_ONLY:
                raise _Skip("screen, log and plot output: the scene writes its energies series and frames")
            if handler is None:
                raise _Skip(f"unknown command {name!r}")
            if self.runs and name not in _AFTER_RUN:
                raise _Skip(f"{name}(...) after the run of line {self.runs[0][0]}: a scene is one run; "
                            "after a run only fixes of nodes (velocity_nodes, force_nodes), regions, groups, "
                            "dumps and further runs are translated")
            added = {id(c) for c in self.conditions + self.loads}
            handler(arguments)
            if self.runs and name == "fix":
                self.late += [(number, where, item) for where in (self.conditions, self.loads)
                              for item in where if id(item) not in added]
        except _Skip as skip:
            self.skip(str(skip))

    def skip(self, reason: str, line: int | None = None) -> None:
        number = self.line if line is None else line
        self.untranslated.append(Untranslated(number, self.lines.get(number, ""), reason))

    def note(self, text: str, line: int | None = None) -> None:
        number = self.line if line is None else line
        self.notes.append(Untranslated(number, self.lines.get(number, ""), text))

    def assign(self, name: str, text: str) -> None:
        """A variable: a number, or (in x, y, z, time) a named expression of the scene."""
        value = self.value(text)
        if value.runtime:
            self.variables[name] = value
            raise _Skip(value.runtime)
        if value.number is None:
            scene_name = name if name not in _RESERVED else f"{name}_k"
            while self.definitions.get(scene_name, value.text) != value.text:   # defined again: a new name
                scene_name += "_"
            self.definitions[scene_name] = value.text
            value = _Value(scene_name, None)
        self.variables[name] = value

    # -- expressions ---------------------------------------------------------

    def value(self, text: str) -> _Value:
        """A Karamelo expression in the scene's syntax (its variables in x, y, z, t by their scene
        names); runtime values carry their reason."""
        pieces, position, runtime = [], 0, None
        while position < len(text):
            match = _TOKEN.match(text, position)
            if match is None:
                raise KarameloError(f"line {self.line}: unexpected character {text[position]!r} in {text!r}")
            position = match.end()
            word = match.group("name")
            if not match.group(0).strip():
                continue
            if word is None:
                pieces.append({"^": "**"}.get(match.group(0), match.group(0)))
                continue
            known = self.variables.get(word)
            if known is not None:
                runtime = runtime or known.runtime
                pieces.append(repr(known.number) if known.number is not None else known.text)
            elif word in _RUNTIME_FUNCTIONS:
                runtime = f"{word}() is {_RUNTIME_FUNCTIONS[word]}, computed during a Karamelo run"
                pieces.append(word)
            elif word.split("_")[0] in self.outputs and (word in self.outputs or "_" in word):
                runtime = f"{word} is the output of {self.outputs[word.split('_')[0]]}, computed during a Karamelo run"
                pieces.append(word)
            else:
                pieces.append(_BUILTINS.get(word, word))
        scene_text = " ".join(pieces)
        if runtime:
            return _Value(scene_text, None, runtime)
        if len(scene_text) > MAX_LENGTH:
            return _Value(scene_text, None, f"{text.strip()[:40]!r}... is longer than the scene's "
                                            f"{MAX_LENGTH} characters for an expression")
        try:
            compiled = compile_expression(scene_text, SCENE_VARIABLES, self.definitions)
        except ExpressionError as exc:
            raise KarameloError(f"line {self.line}: cannot read {text.strip()!r}: {exc}") from None
        number = None if compiled.variables_used else float(compiled.evaluate())
        return _Value(scene_text, number)

    def uses(self, text: str) -> set[str]:
        """The variables (x, y, z, X, Y, Z, t) a scene text uses, through the named expressions."""
        return set(compile_expression(text, SCENE_VARIABLES, self.definitions).variables_used)

    def number(self, text: str, what: str) -> float:
        value = self.value(text)
        if value.runtime:
            raise _Skip(f"{what}: {value.runtime}")
        if value.number is None:
            raise _Skip(f"{what} must be a number, not an expression in x, y, z or time: {text!r}")
        return value.number

    def component(self, text: str, variables: tuple[str, ...], what: str) -> float | str | None:
        """A vector component: NULL (None), a number, or an expression in `variables`."""
        if text == "NULL":
            return None
        value = self.value(text)
        if value.runtime:
            raise _Skip(f"{what}: {value.runtime}")
        if value.number is not None:
            return value.number
        used = self.uses(value.text)
        if not used <= set(variables):
            raise _Skip(f"{what} depends on {', '.join(sorted(used - set(variables)))}; the scene's {what} "
                        f"may depend on {', '.join(variables)} only")
        return value.text

    def vector(self, arguments: list[str], variables: tuple[str, ...], what: str) -> list:
        if self.dimension is None:
            raise _Skip("before dimension(...)")
        if len(arguments) < self.dimension:
            raise _Skip(f"{what} needs {self.dimension} components, {len(arguments)} given")
        return [self.component(a, variables, what) for a in arguments[:self.dimension]]

    def reference(self, text: str) -> str:
        """The same expression with x, y, z read as the reference position X, Y, Z: a named
        expression that reads them becomes its copy `<name>_0` in X, Y, Z."""
        def word(match: re.Match) -> str:
            name = match.group(0)
            if name in ("x", "y", "z"):
                return name.upper()
            if name in self.definitions and self.uses(name) & {"x", "y", "z"}:
                copy = f"{name}_0"
                if copy not in self.definitions:
                    self.definitions[copy] = self.reference(self.definitions[name])
                return copy
            return name
        return _SCENE_NAME.sub(word, text)

    # -- method, domain --------------------------------------------------------

    def cmd_method(self, a: list[str]) -> None:
        formulation = a[0].lower()
        if formulation not in ("ulmpm", "tlmpm"):
            raise _Skip(f"method {a[0]!r}: the scene has ulmpm and tlmpm")
        transfer = _TRANSFERS.get(a[1].lower()) if len(a) > 1 else None
        shape = _SHAPES.get(a[2].lower()) if len(a) > 2 else None
        if transfer is None or shape is None:
            raise _Skip(f"transfer {a[1:2]} or shape function {a[2:3]} has no scene equivalent")
        self.method.update(formulation=formulation, transfer=transfer, shape_function=shape)
        if transfer == "flip":
            if len(a) < 4:
                raise _Skip("FLIP without its ratio (the fourth argument)")
            self.method["flip_ratio"] = self.number(a[3], "the FLIP ratio")

    def cmd_scheme(self, a: list[str]) -> None:
        if a[0].lower() not in ("musl", "usl", "usf"):
            raise _Skip(f"scheme {a[0]!r}: the scene has musl, usl and usf")
        self.method["scheme"] = a[0].lower()

    def cmd_dimension(self, a: list[str]) -> None:
        dim = int(self.number(a[0], "the dimension"))
        if dim not in (1, 2, 3):
            raise _Skip(f"dimension {dim}")
        self.dimension = dim
        if len(a) == 1:
            return                        # tlmpm: each solid's cell size; the scene's grid covers the bodies
        if len(a) != 2 * dim + 2:
            raise _Skip(f"dimension({dim}, ...) takes {2 * dim} bounds and a cell size, {len(a) - 1} given")
        bounds = [self.number(v, "a domain bound") for v in a[1:-1]]
        self.grid = {"lower": bounds[0::2], "upper": bounds[1::2], "cell_size": self.number(a[-1], "the cell size")}

    def cmd_region(self, a: list[str]) -> None:
        name, kind, rest = a[0], a[1], a[2:]
        dim = self.dimension
        if dim is None:
            raise _Skip("before dimension(...)")
        if kind == "block":
            if len(rest) < 2 * dim:
                raise _Skip(f"a block needs {2 * dim} bounds")
            bounds = [self._bound(v, k % 2 == 1) for k, v in enumerate(rest[:2 * dim])]
            self.regions[name] = {"type": "box", "lower": bounds[0::2], "upper": bounds[1::2]}
            if rest[2 * dim:]:
                self.skip(f"region {name!r}: arguments {', '.join(rest[2 * dim:])} after the block's bounds "
                          "are not read (the block is)")
        elif kind == "cylinder" and dim == 2:
            exterior = rest[3:] == ["exterior"]
            if len(rest) != 3 and not exterior:
                raise _Skip("a 2D cylinder (disk) is cx, cy, R")
            self.regions[name] = {"type": "sphere", "center": [self.number(v, "a centre") for v in rest[:2]],
                                  "radius": self.number(rest[2], "the radius"), "exterior": exterior}
        elif kind == "cylinder" and dim == 3 and len(rest) == 6 and rest[0] in ("x", "y", "z"):
            axis = "xyz".index(rest[0])
            across = [self.number(v, "a centre") for v in rest[1:3]]
            low, high = self.number(rest[4], "an end"), self.number(rest[5], "an end")
            center = across[:axis] + [(low + high) / 2] + across[axis:]
            self.regions[name] = {"type": "cylinder", "center": center, "radius": self.number(rest[3], "the radius"),
                                  "axis": axis, "height": high - low}
        elif kind == "sphere" and len(rest) == dim + 1:
            self.regions[name] = {"type": "sphere", "center": [self.number(v, "a centre") for v in rest[:dim]],
                                  "radius": self.number(rest[dim], "the radius")}
        else:
            raise _Skip(f"region type {kind!r} with {len(rest)} arguments in {dim}D")

    def _bound(self, text: str, upper: bool) -> float:
        """INF is unbounded on its side (-inf where a lower bound is expected), -INF below."""
        if text in ("INF", "-INF"):
            return INF if upper and text == "INF" else -INF
        return self.number(text, "a block bound")

    def geometry(self, region: str, what: str) -> dict:
        spec = self.regions.get(region)
        if spec is None:
            raise _Skip(f"unknown region {region!r}")
        if spec.get("exterior"):
            raise _Skip(f"region {region!r} is the outside of a cylinder: not a scene geometry")
        if spec["type"] == "box" and not all(map(math.isfinite, spec["lower"] + spec["upper"])):
            raise _Skip(f"region {region!r} is unbounded (INF): {what} needs a bounded one")
        return {k: v for k, v in spec.items() if k != "exterior"}

    def node_region(self, region: str) -> dict:
        """A region as the `where` of grid nodes: a block's INF bounds reach a cell beyond the grid;
        a cylinder's outside (`exterior`) is a box around the grid less the disk."""
        spec = self.regions.get(region)
        if spec is None:
            raise _Skip(f"unknown region {region!r}")
        if spec["type"] != "box":
            inside = {k: v for k, v in spec.items() if k != "exterior"}
            if not spec.get("exterior"):
                return inside
            return {"type": "difference", "parts": [self.around(), inside]}
        lower, upper = self.grid.get("lower"), self.grid.get("upper")
        if lower is None and not all(map(math.isfinite, spec["lower"] + spec["upper"])):
            lower, upper = self.around()["lower"], self.around()["upper"]
        pad = self.grid["cell_size"] if lower is not None else 0.0
        low = [v if math.isfinite(v) else lo - pad for v, lo in zip(spec["lower"], lower or spec["lower"])]
        high = [v if math.isfinite(v) else up + pad for v, up in zip(spec["upper"], upper or spec["upper"])]
        return {"type": "box", "lower": low, "upper": high}

    def around(self) -> dict:
        """A box holding every node of the scene's grid: the grid's bounds, or (a tlmpm grid
        fitted to the bodies: their box and two cells, rounded up) the solids' box and 4 cells."""
        h = self.grid.get("cell_size")
        if self.grid.get("lower") is not None:
            return {"type": "box", "lower": [v - h for v in self.grid["lower"]],
                    "upper": [v + h for v in self.grid["upper"]]}
        if not self.bodies or h is None:
            raise _Skip("a region's outside before any solid (its extent is the solids' grid)")
        boxes = [_bounds(body["geometry"]) for body in self.bodies.values()]
        return {"type": "box", "lower": [min(b[0][a] for b in boxes) - 4 * h for a in range(self.dimension)],
                "upper": [max(b[1][a] for b in boxes) + 4 * h for a in range(self.dimension)]}

    # -- materials, solids, groups ---------------------------------------------

    def cmd_eos(self, a: list[str]) -> None:
        self.parts["eos"][a[0]] = (self.line, a[1:])

    def cmd_strength(self, a: list[str]) -> None:
        self.parts["strength"][a[0]] = (self.line, a[1:])

    def cmd_damage(self, a: list[str]) -> None:
        self.parts["damage"][a[0]] = (self.line, a[1:])

    def cmd_material(self, a: list[str]) -> None:
        name, kind = a[0], a[1].lower()
        if kind in ("linear", "neo-hookean") and len(a) == 5:
            rho, e, nu = (self.number(v, "a material constant") for v in a[2:5])
            model = "linear_elastic" if kind == "linear" else "neo_hookean"
            self.materials[name] = {"model": model, "density": rho, "youngs_modulus": e, "poisson_ratio": nu}
            self.speeds[name] = math.sqrt(e * (1 - nu) / ((1 + nu) * (1 - 2 * nu)) / rho)   # (K + 4/3 G) / rho
        elif kind == "eos-strength" and len(a) in (4, 5):
            self.materials[name], self.speeds[name] = self.eos_strength(*a[2:])
        else:
            raise _Skip(f"material type {a[1]!r} with {len(a) - 2} arguments")

    def _part(self, kind: str, name: str) -> tuple[str, list[float | str]]:
        found = self.parts[kind].get(name)
        if found is None:
            raise _Skip(f"unknown {kind} {name!r}")
        return found[1][0].lower(), found[1][1:]

    def eos_strength(self, eos_name: str, strength_name: str, damage_name: str | None = None
                     ) -> tuple[dict, float]:
        """The material and Karamelo's wave speed sqrt((K + 4/3 G) / rho) for its time step."""
        (eos, e), (strength, s) = self._part("eos", eos_name), self._part("strength", strength_name)

        def n(values: list[str]) -> list[float]:
            return [self.number(v, f"a constant of {eos_name}/{strength_name}") for v in values]

        if (eos, strength) == ("fluid", "fluid") and len(e) == 3 and len(s) == 1 and damage_name is None:
            rho, k, gamma = n(e)
            viscosity = n(s)[0]   # Karamelo's fluid strength G: its time step reads it as a shear modulus
            return ({"model": "fluid", "density": rho, "bulk_modulus": k, "gamma": gamma, "viscosity": viscosity},
                    math.sqrt((k + 4 * viscosity / 3) / rho))
        if (eos, strength) == ("shock", "johnson_cook") and len(e) in (7, 9) and len(s) == 9:
            return self.johnson_cook(n(e), n(s), damage_name, n)
        raise _Skip(f"eos {eos!r} ({len(e)} constants) with strength {strength!r} ({len(s)}): the scene's "
                    "materials have fluid/fluid (fluid: rho, K, gamma; G) and shock/johnson_cook (johnson_cook "
                    "with a Mie-Gruneisen EOS: rho, K, c0, S, Gamma, cv, Tr[, Q1, Q2]; G, A, B, n, eps0dot, C, "
                    "m, Tr, Tm)")

    def johnson_cook(self, e: list[float], s: list[float], damage_name: str | None, n) -> tuple[dict, float]:
        rho, k, c0, slope, gamma0, cv, _ = e[:7]
        if any(e[7:]):
            raise _Skip(f"the shock EOS's artificial viscosity Q1 = {e[7]:g}, Q2 = {e[8]:g}: the scene's "
                        "johnson_cook material has none (translated with Q1 = Q2 = 0 only)")
        g, a_, b, exponent, rate, c, m, room, melt = s
        material = {"model": "johnson_cook", "density": rho,
                    "youngs_modulus": 9 * k * g / (3 * k + g), "poisson_ratio": (3 * k - 2 * g) / (2 * (3 * k + g)),
                    "A": a_, "B": b, "n": exponent, "C": c, "reference_strain_rate": rate,
                    "room_temperature": room, "melt_temperature": melt,
                    "taylor_quinney": 0.0,   # Karamelo heats only with a temperature(...) law: none given
                    "eos": {"model": "mie_gruneisen", "c0": c0, "s": slope, "gamma0": gamma0}}
        # m = 0 is Karamelo's "no thermal softening" and cv = 0 its "no heating": the scene's way
        # of saying so is to leave them out (needed only where a temperature leaves the room's)
        material.update({key: value for key, value in (("m", m), ("specific_heat", cv)) if value != 0})
        if damage_name is not None:
            kind, d = self._part("damage", damage_name)
            if kind != "damage_johnson_cook" or len(d) < 5:
                raise _Skip(f"damage {kind!r}: the scene has Johnson-Cook damage")
            material["damage"] = dict(zip(("D1", "D2", "D3", "D4", "D5"), n(d[:5])))
        return material, math.sqrt((k + 4 * g / 3) / rho)

    def cmd_solid(self, a: list[str]) -> None:
        if len(a) >= 6 and a[1] in ("rectangle", "block", "cylinder", "sphere"):
            current = f"solid({a[0]}, region, {a[2]}, {', '.join(a[3:])})"
            raise KarameloError(
                f"line {self.line}: solid({a[0]}, {a[1]}, ...) is old syntax that Karamelo at {KARAMELO_VERSION} "
                f"no longer reads (a solid is seeded from a region by name): it writes {current}")
        if len(a) < 6 or a[1] != "region":
            raise _Skip(f"solid of type {a[1] if len(a) > 1 else None!r}: the scene seeds solids from a region")
        name, region, ppc, material = a[0], a[2], a[3], a[4]
        if material not in self.materials:
            raise _Skip(f"material {material!r} was not translated")
        cell = self.number(a[5], "the cell size")
        if self.grid.get("cell_size", cell) != cell:
            raise _Skip(f"particles seeded on cells of {cell:g}, the grid's are {self.grid['cell_size']:g}: "
                        "the scene seeds on the grid's cells")
        self.grid.setdefault("cell_size", cell)
        body = {"name": name, "material": material, "geometry": self.geometry(region, "a solid"),
                "particles_per_cell": int(self.number(ppc, "particles per cell"))}
        if len(a) > 6:
            body["initial_temperature"] = self.number(a[6], "the initial temperature")
        self.bodies[name] = body

    def cmd_delete_particles(self, a: list[str]) -> None:
        body = self.bodies.get(a[0])
        if body is None or len(a) != 3 or a[1] != "region":
            raise _Skip("delete_particles(solid, region, name) of a translated solid")
        body["geometry"] = {"type": "difference", "parts": [body["geometry"], self.geometry(a[2], "a deletion")]}

    def cmd_group(self, a: list[str]) -> None:
        if len(a) not in (4, 6) or a[1] not in ("particles", "nodes") or a[2] != "region":
            raise _Skip("group(name, particles|nodes, region, region[, solid, solid]) only")
        self.groups[a[0]] = (a[1], a[3], a[5] if len(a) == 6 else None)

    def group(self, name: str, kind: str) -> tuple[str, str | None]:
        found = self.groups.get(name)
        if found is None or found[0] != kind:
            raise _Skip(f"{name!r} is not a group of {kind}")
        return found[1], found[2]

    # -- fixes, computes ---------------------------------------------------------

    def cmd_fix(self, a: list[str]) -> None:
        kind, arguments = a[1], a[2:]
        self.outputs[a[0]] = f"fix {a[0]!r}"
        if self.runs and kind not in ("velocity_nodes", "force_nodes", "kinetic_energy", "strain_energy"):
            raise _Skip(f"fix {kind!r} after the run of line {self.runs[0][0]}: a scene is one run; after a run "
                        "only velocity_nodes and force_nodes (from t = 0, for a set-up run) are translated")
        if kind in ("kinetic_energy", "strain_energy"):
            self.scene["output"]["energies"] = True
        elif kind == "initial_velocity_particles":
            self.initial_velocity(arguments)
        elif kind == "velocity_nodes":
            region, _ = self.group(arguments[0], "nodes")
            velocity = self.vector(arguments[1:], ("t",), "velocity")
            self.conditions.append({"type": "velocity", "where": self.node_region(region), "velocity": velocity})
        elif kind == "force_nodes":
            self.force_nodes(arguments)
        elif kind == "body_force" and arguments[:1] == ["all"]:
            self.body_force(arguments[1:])
        elif kind == "check_solution":
            raise _Skip("fix check_solution (the error against an exact solution, written to Karamelo's log): "
                        "no scene equivalent; compare the frames with the exact solution")
        else:
            raise _Skip(f"fix {kind!r}: no scene equivalent")

    def force_nodes(self, a: list[str]) -> None:
        """A total force shared equally by the group's nodes (those with mass): the scene's force
        load on the particles that carry it to those nodes, shared by mass."""
        region, solid = self.group(a[0], "nodes")
        if solid is None or solid not in self.bodies:
            raise _Skip(f"group {a[0]!r} is not of one translated solid: the scene's force load is a body's")
        where = self.node_region(region)
        if where["type"] != "box":
            raise _Skip(f"region {region!r} is not a block: the scene's force load acts in a box")
        force = [0.0 if v is None else v for v in self.vector(a[1:], ("t",), "force")]
        # the particles within the shape function's half support of the nodes reach them (linear: a cell)
        reach = self.grid["cell_size"] * _SUPPORT.get(self.method.get("shape_function", "linear"), 1.0)
        around = self.around()
        low = [max(v - reach, lo) for v, lo in zip(where["lower"], around["lower"])]
        high = [min(v + reach, up) for v, up in zip(where["upper"], around["upper"])]
        self.loads.append({"type": "force", "body": solid, "where": {"type": "box", "lower": low, "upper": high},
                           "force": force})
        self.note(f"force_nodes: Karamelo shares the total force equally among the nodes of {a[0]!r} "
                  f"(region {region!r}); here the particles of {solid!r} within {reach:g} of that region "
                  "(those whose shape functions reach its nodes) share it by mass: the same total force, "
                  "spread over the nodes those particles touch")

    def cmd_compute(self, a: list[str]) -> None:
        self.outputs[a[0]] = f"compute {a[0]!r}"
        if a[1] not in ("kinetic_energy", "strain_energy"):
            raise _Skip(f"compute {a[1]!r}: no scene equivalent")
        self.scene["output"]["energies"] = True

    def initial_velocity(self, a: list[str]) -> None:
        region, solid = self.group(a[0], "particles")
        body = self.bodies.get(solid)
        if body is None or self.geometry(region, "a group") != _base_geometry(body["geometry"]):
            raise _Skip(f"group {a[0]!r} is not all of a translated solid: the scene's initial velocity is a body's")
        velocity = [0.0 if v is None else v for v in self.vector(a[1:], ("x", "y", "z"), "initial velocity")]
        body["initial_velocity"] = velocity

    def body_force(self, a: list[str]) -> None:
        components = [0.0 if v is None else v for v in self.vector(a, ("x", "y", "z", "X", "Y", "Z", "t"),
                                                                   "body force")]
        if all(isinstance(v, float) for v in components):
            self.scene["gravity"] = components
            return
        if self.method.get("formulation") == "tlmpm" and any(
                isinstance(v, str) and self.uses(v) & {"x", "y", "z"} for v in components):
            # Karamelo evaluates a body force at the grid's nodes: in TLMPM they stay where they
            # were, so its x, y, z there are the reference position
            components = [self.reference(v) if isinstance(v, str) else v for v in components]
            self.note("body force in x, y, z with tlmpm: Karamelo evaluates it at the nodes of the reference "
                      "grid, so x, y, z are written X, Y, Z (the reference position)")
        self.scene["body_force"] = [v if isinstance(v, str) else repr(v) for v in components]

    # -- time, output ----------------------------------------------------------

    def cmd_set_dt(self, a: list[str]) -> None:
        self.scene["time"]["dt"] = self.number(a[0], "the time step")

    def cmd_dt_factor(self, a: list[str]) -> None:
        # dt = factor h / max(c + |v|) with Karamelo's c: the scene's cfl is set at the end (finish)
        self.dt_factor = (self.line, self.number(a[0], "the time step factor"))

    def cmd_run_time(self, a: list[str]) -> None:
        self.runs.append((self.line, "time", self.number(a[0], "the run time")))   # that much more time

    def cmd_run(self, a: list[str]) -> None:
        self.runs.append((self.line, "steps", self.number(a[0], "the steps")))

    def cmd_dump(self, a: list[str]) -> None:
        if len(a) < 5 or a[2] != "particle":
            raise _Skip(f"a {a[2] if len(a) > 2 else ''} dump: the results hold particle fields")
        self.dumps.append((self.line, int(self.number(a[3], "the dump interval"))))
        # the scene's own fields stay (stress: `mpm preview --field von_mises`), the dump's are added
        fields = self.scene["output"].setdefault("fields", ["position", "velocity", "stress"])
        unknown = []
        for name in a[5:]:
            mapped = _DUMP_FIELDS.get(name)
            if mapped is None:
                unknown.append(name)
            elif mapped not in fields:
                fields.append(mapped)
        if unknown:
            self.skip(f"dump fields {', '.join(unknown)}: no scene output field of that name")

    # -- the scene -------------------------------------------------------------

    def finish(self) -> Translation:
        scene = {"version": 1, "name": f"{self.name} (imported from Karamelo)", "dimension": self.dimension,
                 "method": self.method, "grid": self.grid, "materials": self.materials,
                 "bodies": list(self.bodies.values()), "boundary_conditions": self.conditions}
        if self.loads:
            scene["loads"] = self.loads
        scene.update({k: v for k, v in self.scene.items() if v})
        scene["time"] = dict(self.scene["time"])
        used = self.used_definitions(scene)
        if used:
            scene["expressions"] = {name: text for name, text in self.definitions.items() if name in used}
        self.initial = initial = self.time_step(scene)
        total = self.end(scene, initial)
        self.late_commands(scene, total)
        if self.dumps:
            self.frames(scene, initial)
        return Translation(scene, self.untranslated, self.notes)

    def time_step(self, scene: dict) -> float | None:
        """`set_dt`, or the cfl giving Karamelo's first step dt_factor h / max c with its wave speed
        sqrt((K + 4/3 G) / rho) (the scene's may differ: rho c0^2 for a Mie-Gruneisen bulk modulus,
        K gamma for a Tait fluid); the first step, None where the scene cannot tell it yet."""
        time = scene["time"]
        if time.get("dt") is not None:
            return time["dt"]
        line, factor = self.dt_factor or (0, DEFAULT_DT_FACTOR)
        probe = _probe(scene, cfl=1.0)
        if probe is None:
            return None
        from solver.stability import stable_limit

        ours = max(probe.materials[b.material].initial_wave_speed(b) for b in probe.bodies)
        theirs = max(self.speeds[b.material] for b in probe.bodies)
        time["cfl"] = factor * ours / theirs
        if abs(ours / theirs - 1) > 1e-6:
            self.note(f"Karamelo's step is dt_factor h / max c with c = sqrt((K + 4/3 G) / rho) = {theirs:.6g}; "
                      f"the scene's wave speed is {ours:.6g}: time.cfl = {time['cfl']:.6g} gives the same step",
                      line=line)
        elif self.dt_factor is None:
            self.note(f"no dt_factor: Karamelo's default {DEFAULT_DT_FACTOR} is time.cfl", line=0)
        if time["cfl"] > 1:   # the scene's largest: a step a little smaller than Karamelo's, no other change
            self.note(f"dt_factor {factor:g} is time.cfl = {time['cfl']:.6g} in the scene's terms, above its largest, "
                      f"1: the step is {100 * (1 - 1 / time['cfl']):.3g} % smaller than Karamelo's", line=line)
            time["cfl"] = 1.0
        limit = stable_limit(probe)
        return None if limit is None else time["cfl"] * limit.dt

    def end(self, scene: dict, initial: float | None) -> float | None:
        """time.end from the runs one after the other: run_time(T) is T more, run(N) N steps more
        (with an adaptive step: N times the first step, noted)."""
        if not self.runs:
            self.skip("no run_time(...) or run(...): the scene needs time.end", line=0)
            return None
        total, fixed = 0.0, scene["time"].get("dt") is not None
        for line, kind, amount in self.runs:
            if kind == "time":
                total += amount
            elif initial is None:
                self.skip("run(N steps) with an adaptive time step whose first step the scene cannot tell "
                          "yet (see its other errors): the scene's end is a time", line=line)
                return None
            else:
                total += amount * initial
                if not fixed:
                    self.note(f"{amount:g} steps with an adaptive step: time.end adds {amount:g} times the first step "
                              f"{initial:.6g} (the step changes as the bodies deform: about {amount:g} steps)",
                              line=line)
        scene["time"]["end"] = total
        return total

    def late_commands(self, scene: dict, total: float | None) -> None:
        """Fixes after a first run act from t = 0 where that run is a set-up run (at most LATE_SHARE
        of the whole: Karamelo's way to have the grid's nodes before grouping them); otherwise
        they are taken out again and listed."""
        if not self.late:
            return
        for line, where, item in self.late:
            before = self.elapsed(line, scene)
            if total and before is not None and before <= LATE_SHARE * total:
                self.note(f"after the run(s) before it ({before:.6g} of {total:.6g}, a set-up run): applied "
                          "from t = 0 (Karamelo applies it from then on)", line=line)
                continue
            where.remove(item)
            self.skip("after a run that is more than a set-up run: a scene is one run, the condition would "
                      f"act from t = 0 instead of from t = {before if before is not None else '?'}", line=line)
        scene["loads"] = self.loads
        if not self.loads:
            del scene["loads"]

    def elapsed(self, line: int, scene: dict) -> float | None:
        step = self.initial
        before = [amount * step if kind == "steps" and step else amount if kind == "time" else None
                  for run_line, kind, amount in self.runs if run_line < line]
        return None if None in before else sum(before)

    def frames(self, scene: dict, initial: float | None) -> None:
        """A dump every N steps: frames N steps apart (with an adaptive step: N first steps apart,
        noted), the last at the end; at most MAX_FRAMES."""
        line, interval = self.dumps[0]
        end = scene["time"].get("end")
        if end is None or initial is None:
            self.skip("a dump every N steps without an end time or a first step (see the other lines): "
                      "output.frames left at its default", line=line)
            return
        steps = end / initial
        frames = math.ceil(steps / interval - 1e-6) + 1
        if frames > MAX_FRAMES:
            self.note(f"a dump every {interval} steps is {frames} frames: the scene writes {MAX_FRAMES} "
                      f"(every {math.ceil(steps / (MAX_FRAMES - 1))} steps or so)", line=line)
            frames = MAX_FRAMES
        elif scene["time"].get("dt") is None:
            self.note(f"a dump every {interval} steps with an adaptive step: {frames} frames evenly spaced in "
                      f"time, {interval} first steps apart", line=line)
        elif abs(steps - round(steps)) < 1e-6 and round(steps) % interval:
            self.note(f"a dump every {interval} steps of {round(steps)}: the scene's frames are evenly spaced "
                      "and include the last step", line=line)
        scene["output"]["frames"] = max(2, frames)
        for other, _ in self.dumps[1:]:
            self.skip("a second particle dump: the scene has one set of frames (the first dump's)", line=other)

    def used_definitions(self, scene: dict) -> set[str]:
        """The named expressions a translated field uses, and those they use."""
        texts = [v for v in scene.get("body_force") or () if isinstance(v, str)]
        texts += [v for b in scene["bodies"] for v in b.get("initial_velocity") or () if isinstance(v, str)]
        texts += [v for c in scene["boundary_conditions"] for v in c.get("velocity") or () if isinstance(v, str)]
        texts += [v for load in scene.get("loads") or () for v in load["force"] if isinstance(v, str)]
        used: set[str] = set()
        while texts:
            for name in _SCENE_NAME.findall(texts.pop()):
                if name in self.definitions and name not in used:
                    used.add(name)
                    texts.append(self.definitions[name])
        return used


def _probe(scene: dict, cfl: float):
    """The scene as validated with a placeholder end and cfl (to read its wave speeds and first
    step before its end is known); None where it is not valid yet (its errors come later)."""
    from solver.scene import SceneError
    from solver.scene_checks import load_scene

    trial = {**scene, "time": {**scene["time"], "end": 1.0, "cfl": cfl}, "output": {}}
    trial["time"].pop("dt", None)
    try:
        return load_scene(trial, stability=False)
    except (SceneError, ValueError, TypeError):
        return None


def _bounds(geometry: dict) -> tuple[list[float], list[float]]:
    """The box of a translated solid's geometry (a box, disk, sphere, cylinder, or a difference:
    its first part)."""
    kind = geometry["type"]
    if kind == "difference":
        return _bounds(geometry["parts"][0])
    if kind == "box":
        return geometry["lower"], geometry["upper"]
    r, center = geometry["radius"], geometry["center"]
    if kind == "cylinder":
        half = [r] * len(center)
        half[geometry["axis"]] = geometry["height"] / 2
        return [c - h for c, h in zip(center, half)], [c + h for c, h in zip(center, half)]
    return [c - r for c in center], [c + r for c in center]


def _base_geometry(geometry: dict) -> dict:
    """A solid's region (the first part where particles were deleted from it)."""
    return geometry["parts"][0] if geometry.get("type") == "difference" else geometry


def _split(arguments: str) -> list[str]:
    """Comma-separated arguments, commas inside parentheses kept."""
    parts, depth, start = [], 0, 0
    for k, char in enumerate(arguments):
        depth += {"(": 1, ")": -1}.get(char, 0)
        if char == "," and depth == 0:
            parts.append(arguments[start:k].strip())
            start = k + 1
    parts.append(arguments[start:].strip())
    return [p for p in parts if p]
