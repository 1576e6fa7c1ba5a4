"""Translate a Karamelo input file (LAMMPS-style commands) into a scene: `mpm import karamelo`.

A Karamelo file is a list of variable definitions (`E = 1e+3`, `hL = 0.5*L`) and
commands (`region(rBall1, cylinder, -hL+R, -hL+R, R)`). Expressions are read by the
scene's own expression parser (solver/expressions.py, a whitelist, never eval): a
Karamelo expression is first rewritten token by token into the scene's syntax (`^` is
`**`, `PI` is `pi`, `time` is `t`, a variable is its value or, when it depends on x, y,
z or time, its parenthesised definition), then compiled; with no variable left it is
evaluated to a number.

What a command means is translated only where the scene has the same thing; every
other line is listed with its number and the reason (`Translation.untranslated`),
and nothing is guessed: a missing value stays missing and the scene's validation says
so. The commands and their Karamelo semantics are those of Karamelo's paper ([K] 3.4,
Appendix A) and its example files (tests/data/karamelo/).
"""
from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

from solver.errors import SolverError
from solver.expressions import MAX_LENGTH, ExpressionError, compile_expression

SCENE_VARIABLES = ("x", "y", "z", "t")
_TOKEN = re.compile(r"\s+|(?P<number>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)|(?P<name>[A-Za-z_]\w*)|(?P<op>[-+*/^(),])")
_ASSIGNMENT = re.compile(r"^\s*([A-Za-z_]\w*)\s*=(?!=)\s*(.*)$")
_COMMAND = re.compile(r"^\s*([A-Za-z_]\w*)\s*\((.*)\)\s*$")
# Karamelo functions whose value is computed during a run: no scene equivalent.
_RUNTIME_FUNCTIONS = {"xcm": "a group's centre of mass", "value": "a value frozen during the run"}
_SHAPES = {"linear": "linear", "cubic-spline": "cubic_bspline", "quadratic-spline": "quadratic_bspline",
           "bernstein-quadratic": "bernstein"}
_TRANSFERS = {"flip": "flip", "pic": "pic", "apic": "apic"}
_DUMP_FIELDS = {"x": "position", "y": "position", "z": "position", "vx": "velocity", "vy": "velocity",
                "vz": "velocity", "s11": "stress", "s22": "stress", "s33": "stress", "s12": "stress",
                "s13": "stress", "s23": "stress", "seq": "von_mises", "volume": "volume", "mass": "mass",
                "damage": "damage", "T": "temperature", "ienergy": "strain_energy_density"}
_OUTPUT_ONLY = ("set_output", "log", "log_modify", "plot", "save_plot")
INF = float("inf")


class KarameloError(SolverError, ValueError):
    """A file that cannot be read at all (not a translation problem): names the line."""


@dataclass
class Untranslated:
    line: int
    text: str
    reason: str


@dataclass
class Translation:
    scene: dict
    untranslated: list[Untranslated] = field(default_factory=list)


class _Skip(Exception):
    """The current line (or part of it) has no translation: the reason."""


@dataclass
class _Value:
    text: str                  # in the scene's expression syntax
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
        self.dimension: int | None = None
        self.method: dict = {"scheme": "musl"}   # Karamelo's default scheme is MUSL ([K] 3.7, Remark 2)
        self.grid: dict = {}
        self.regions: dict[str, dict] = {}
        self.parts: dict[str, dict[str, tuple[int, list]]] = {"eos": {}, "strength": {}, "damage": {}}
        self.materials: dict[str, dict] = {}
        self.bodies: dict[str, dict] = {}
        self.groups: dict[str, tuple[str, str, str | None]] = {}
        self.conditions: list[dict] = []
        self.scene: dict = {"time": {}, "output": {}}
        self.dump: tuple[int, int] | None = None   # (line, steps between dumps)
        self.ran_at: int | None = None
        self.lines: dict[int, str] = {}
        self.outputs: dict[str, str] = {}   # fix and compute ids: their values exist during a run only
        self.line = 0

    # -- lines ---------------------------------------------------------------

    def read(self, number: int, line: str) -> None:
        self.line = number
        self.lines[number] = line
        try:
            assignment = _ASSIGNMENT.match(line)
            if assignment:
                value = self.variables[assignment.group(1)] = self.value(assignment.group(2))
                if value.runtime:
                    raise _Skip(value.runtime)
                return
            command = _COMMAND.match(line)
            if not command:
                raise KarameloError(f"line {number}: neither a variable definition (name = expression) "
                                    f"nor a command (name(arguments)): {line!r}")
            name, arguments = command.group(1), _split(command.group(2))
            if self.ran_at is not None:
                raise _Skip(f"after the run of line {self.ran_at}: a scene is one run, Karamelo goes on with "
                            "the same simulation")
            handler = getattr(self, f"cmd_{name}", None)
            if name in _OUTPUT_ONLY:
                raise _Skip("screen, log and plot output: the scene writes its energies series and frames")
            if handler is None:
                raise _Skip(f"unknown command {name!r}")
            handler(arguments)
        except _Skip as skip:
            self.skip(str(skip))

    def skip(self, reason: str, line: int | None = None) -> None:
        number = self.line if line is None else line
        self.untranslated.append(Untranslated(number, self.lines.get(number, ""), reason))

    # -- expressions ---------------------------------------------------------

    def value(self, text: str) -> _Value:
        """A Karamelo expression in the scene's syntax; runtime values carry their reason."""
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
                pieces.append(repr(known.number) if known.number is not None else f"({known.text})")
            elif word in _RUNTIME_FUNCTIONS:
                runtime = f"{word}() is {_RUNTIME_FUNCTIONS[word]}, computed during a Karamelo run"
                pieces.append(word)
            elif word.split("_")[0] in self.outputs and (word in self.outputs or "_" in word):
                runtime = f"{word} is the output of {self.outputs[word.split('_')[0]]}, computed during a Karamelo run"
                pieces.append(word)
            else:
                pieces.append({"PI": "pi", "time": "t"}.get(word, word))
        scene_text = " ".join(pieces)
        if runtime:
            return _Value(scene_text, None, runtime)
        if len(scene_text) > MAX_LENGTH:
            return _Value(scene_text, None, f"written out, {text.strip()[:40]!r}... is longer than the scene's "
                                            f"{MAX_LENGTH} characters for an expression")
        try:
            compiled = compile_expression(scene_text, SCENE_VARIABLES)
        except ExpressionError as exc:
            raise KarameloError(f"line {self.line}: cannot read {text.strip()!r}: {exc}") from None
        number = None if compiled.variables_used else float(compiled.evaluate())
        return _Value(scene_text, number)

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
        used = compile_expression(value.text, SCENE_VARIABLES).variables_used
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

    def node_box(self, region: str) -> dict:
        """A region as the `where` box of nodes; INF bounds reach a cell beyond the grid."""
        spec = self.regions.get(region)
        if spec is None or spec["type"] != "box":
            raise _Skip(f"region {region!r} is not a block: a node condition's region is a box in the scene")
        lower, upper = self.grid.get("lower"), self.grid.get("upper")
        if lower is None and not all(map(math.isfinite, spec["lower"] + spec["upper"])):
            raise _Skip("an unbounded (INF) block without the grid's bounds (dimension gave none)")
        pad = self.grid["cell_size"] if lower is not None else 0.0
        low = [v if math.isfinite(v) else lo - pad for v, lo in zip(spec["lower"], lower or spec["lower"])]
        high = [v if math.isfinite(v) else up + pad for v, up in zip(spec["upper"], upper or spec["upper"])]
        return {"type": "box", "lower": low, "upper": high}

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
        elif kind == "eos-strength" and len(a) in (4, 5):
            self.materials[name] = self.eos_strength(*a[2:])
        else:
            raise _Skip(f"material type {a[1]!r} with {len(a) - 2} arguments")

    def _part(self, kind: str, name: str) -> tuple[str, list[float | str]]:
        found = self.parts[kind].get(name)
        if found is None:
            raise _Skip(f"unknown {kind} {name!r}")
        return found[1][0].lower(), found[1][1:]

    def eos_strength(self, eos_name: str, strength_name: str, damage_name: str | None = None) -> dict:
        (eos, e), (strength, s) = self._part("eos", eos_name), self._part("strength", strength_name)

        def n(values: list[str]) -> list[float]:
            return [self.number(v, f"a constant of {eos_name}/{strength_name}") for v in values]

        if (eos, strength) == ("fluid", "fluid") and len(e) == 3 and len(s) == 1 and damage_name is None:
            rho, k, gamma = n(e)
            return {"model": "fluid", "density": rho, "bulk_modulus": k, "gamma": gamma, "viscosity": n(s)[0]}
        if (eos, strength) == ("shock", "johnson_cook") and len(e) >= 7 and len(s) == 9:
            rho, k, c0, slope, gamma0, cv, _ = n(e[:7])
            g, a_, b, exponent, rate, c, m, room, melt = n(s)
            material = {"model": "johnson_cook", "density": rho,
                        "youngs_modulus": 9 * k * g / (3 * k + g), "poisson_ratio": (3 * k - 2 * g) / (2 * (3 * k + g)),
                        "A": a_, "B": b, "n": exponent, "C": c, "reference_strain_rate": rate, "m": m,
                        "room_temperature": room, "melt_temperature": melt, "specific_heat": cv,
                        "taylor_quinney": 0.0,   # Karamelo heats only with a temperature(...) law: none given
                        "eos": {"model": "mie_gruneisen", "c0": c0, "s": slope, "gamma0": gamma0}}
            if damage_name is not None:
                kind, d = self._part("damage", damage_name)
                if kind != "damage_johnson_cook" or len(d) < 5:
                    raise _Skip(f"damage {kind!r}: the scene has Johnson-Cook damage")
                material["damage"] = dict(zip(("D1", "D2", "D3", "D4", "D5"), n(d[:5])))
            return material
        raise _Skip(f"eos {eos!r} with strength {strength!r}: the scene's materials have fluid/fluid "
                    "(fluid) and shock/johnson_cook (johnson_cook with a Mie-Gruneisen EOS)")

    def cmd_solid(self, a: list[str]) -> None:
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
        if kind in ("kinetic_energy", "strain_energy"):
            self.scene["output"]["energies"] = True
        elif kind == "initial_velocity_particles":
            self.initial_velocity(arguments)
        elif kind == "velocity_nodes":
            region, _ = self.group(arguments[0], "nodes")
            velocity = self.vector(arguments[1:], ("t",), "velocity")
            self.conditions.append({"type": "velocity", "where": self.node_box(region), "velocity": velocity})
        elif kind == "body_force" and arguments[:1] == ["all"]:
            self.body_force(arguments[1:])
        else:
            raise _Skip(f"fix {kind!r}" + (" (a total force shared equally by the group's nodes; the scene's "
                                           "force load shares it by mass among particles: the same total, "
                                           "another load)" if kind == "force_nodes" else ": no scene equivalent"))

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
        components = [0.0 if v is None else v for v in self.vector(a, ("x", "y", "z", "t"), "body force")]
        if all(isinstance(v, float) for v in components):
            self.scene["gravity"] = components
            return
        if self.method.get("formulation") == "tlmpm" and any(
                set(compile_expression(str(v), SCENE_VARIABLES).variables_used) & {"x", "y", "z"}
                for v in components):
            raise _Skip("a body force in x, y, z with tlmpm: whether Karamelo reads the current or the "
                        "reference position is not in the file")
        self.scene["body_force"] = [v if isinstance(v, str) else repr(v) for v in components]

    # -- time, output ----------------------------------------------------------

    def cmd_set_dt(self, a: list[str]) -> None:
        self.scene["time"]["dt"] = self.number(a[0], "the time step")

    def cmd_dt_factor(self, a: list[str]) -> None:
        self.scene["time"]["cfl"] = self.number(a[0], "the time step factor")   # dt = factor h / c, as cfl

    def cmd_run_time(self, a: list[str]) -> None:
        self.scene["time"]["end"] = self.number(a[0], "the run time")
        self.ran_at = self.line

    def cmd_run(self, a: list[str]) -> None:
        dt = self.scene["time"].get("dt")
        if dt is None:
            raise _Skip("run(N steps) with an adaptive time step: the scene's end is a time")
        self.scene["time"]["end"] = self.number(a[0], "the steps") * dt
        self.ran_at = self.line

    def cmd_dump(self, a: list[str]) -> None:
        if len(a) < 5 or a[2] != "particle":
            raise _Skip(f"a {a[2] if len(a) > 2 else ''} dump: the results hold particle fields")
        self.dump = (self.line, int(self.number(a[3], "the dump interval")))
        fields, unknown = [], []
        for name in a[5:]:
            mapped = _DUMP_FIELDS.get(name)
            if mapped is None:
                unknown.append(name)
            elif mapped not in fields:
                fields.append(mapped)
        if fields:
            self.scene["output"]["fields"] = fields
        if unknown:
            self.skip(f"dump fields {', '.join(unknown)}: no scene output field of that name")

    # -- the scene -------------------------------------------------------------

    def finish(self) -> Translation:
        scene = {"version": 1, "name": f"{self.name} (imported from Karamelo)", "dimension": self.dimension,
                 "method": self.method, "grid": self.grid, "materials": self.materials,
                 "bodies": list(self.bodies.values()), "boundary_conditions": self.conditions}
        scene.update({k: v for k, v in self.scene.items() if v})
        if "end" not in self.scene["time"]:
            self.skip("no run_time(...) or run(...): the scene needs time.end", line=self.ran_at or 0)
        if self.dump is not None:
            self.frames(scene)
        return Translation(scene, self.untranslated)

    def frames(self, scene: dict) -> None:
        line, interval = self.dump
        time = scene.get("time", {})
        if time.get("dt") is None or time.get("end") is None:
            self.skip("a dump every N steps with an adaptive time step: the scene's frames are evenly spaced "
                      "in time (output.frames left at its default)", line=line)
            return
        steps = math.ceil(time["end"] / time["dt"] - 1e-6)
        if steps % interval:
            self.skip(f"a dump every {interval} steps of {steps}: the scene's frames include the last step",
                      line=line)
            return
        scene["output"]["frames"] = steps // interval + 1


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
