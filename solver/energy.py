"""The energy balance of a run, as a sum over registered terms.

Each term is an energy the bodies hold now (STORED: kinetic, strain, the tools' penalty),
an energy they dissipated since t = 0 (DISSIPATED: the work of plastic flow) or a work
done on them since t = 0 (WORK: the loads and gravity, the boundary conditions and
rigid bodies, damping, friction, tools, a pore fluid's pressure). Energy is conserved when

    balance = sum(stored) + sum(dissipated) - sum(work) = the stored energy at t = 0

and `energy_error` = balance - initial is what the discretisation (and any process
no term counts yet) made or lost. A physics that stores
or exchanges energy registers its term here once (`register`): the series, the
growth check and every display of the balance then include it. The work terms are
kept in the simulation's WorkLedger (`sim.work`), which the phases and hooks add to and
checkpoints keep, each by its term's name.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

from solver.materials import plastic_work
from solver.materials.ideal_gas import grid_density
from solver.pore_fluid_schema import saturated

STORED, DISSIPATED, WORK = "stored", "dissipated", "work"


def _always(scene: Any) -> bool:
    return True


@dataclass(frozen=True)
class Term:
    name: str                                   # its time-series column
    kind: str                                   # STORED, DISSIPATED or WORK
    local: Callable[[Any], float]               # this process's share, from the simulation
    present: Callable[[Any], bool] = _always    # whether a scene has it (a column of its series)


def _kinetic(sim) -> float:
    from solver import kernels
    return kernels.kinetic_energy(sim.particles.mass, sim.particles.v)


def _strain(sim) -> float:
    return sum(material.strain_energy(sim.particles, sl) for material, sl in sim.materials)


def _ledger(name: str) -> Callable[[Any], float]:
    """A WORK term's local share: its entry of the simulation's WorkLedger."""
    return lambda sim: sim.work[name]


TERMS: list[Term] = [
    Term("kinetic_energy", STORED, _kinetic),
    Term("strain_energy", STORED, _strain),
    Term(plastic_work.NAME, DISSIPATED, plastic_work.local, plastic_work.present),   # the return mappings
    Term("external_work", WORK, _ledger("external_work")),     # gravity, body forces, loads
    Term("boundary_work", WORK, _ledger("boundary_work")),     # walls, velocity conditions, rigid bodies
    Term("damping_work", WORK, _ledger("damping_work"), lambda scene: scene.damping is not None),
    Term("friction_work", WORK, _ledger("friction_work"), lambda scene: frictional(scene)),   # solver/contact.py
    Term("tool_work", WORK, _ledger("tool_work"), lambda scene: bool(scene.tools)),   # solver/tools.py
    Term("tool_penalty_energy", STORED, lambda sim: sim.tools.stored_energy(sim), lambda scene: bool(scene.tools)),
    # a saturated soil's pore pressure on the mixture, sum dt sum_p V_p p_p tr(L_p) (solver/pore_fluid.py):
    # negative while the skeleton compresses, the share of the loads' work the pore water takes
    # (stored in it while undrained, dissipated by Darcy flow as it drains)
    Term("pore_pressure_work", WORK, _ledger("pore_pressure_work"), saturated),
    # the internal energy a gas's density from the grid moved along the adiabat (solver/gas_density.py)
    Term("gas_density_work", WORK, _ledger("gas_density_work"), grid_density),
]


def frictional(scene) -> bool:
    """Whether friction can act: contact with a field per body, or a frictional wall."""
    return scene.contact.fields or any(getattr(bc, "mode", None) == "friction" for bc in scene.boundary_conditions)


def register(term: Term) -> None:
    """Add a term (or replace the one of the same name)."""
    TERMS[:] = [t for t in TERMS if t.name != term.name] + [term]


def terms(scene) -> list[Term]:
    return [t for t in TERMS if t.present(scene)]


class WorkLedger:
    """The work done on the bodies since t = 0, by the name of its WORK term: this process's
    share of each, which the phases and hooks add to as they do the work (`measure` sums the
    shares over the processes). A checkpoint keeps the totals (`totals`); a resumed run gives
    each total to one process and nothing to the others (`restore`), so that the sums go on
    from them."""

    def __init__(self, scene):
        self._shares = {t.name: 0.0 for t in terms(scene) if t.kind == WORK}

    def add(self, name: str, value: float) -> None:
        self._shares[name] += value

    def __getitem__(self, name: str) -> float:
        return self._shares[name]

    def totals(self, domain) -> dict[str, float]:
        """Every term's total over the processes (collective: every process calls it)."""
        names = list(self._shares)
        return {name: float(v) for name, v in zip(names, domain.sum([self._shares[n] for n in names]))}

    def restore(self, totals: dict[str, float], keeps: bool) -> None:
        """The totals of a checkpoint, kept by this process where `keeps` (one process), else zeros."""
        for name in self._shares:
            self._shares[name] = float(totals.get(name, 0.0)) if keeps else 0.0


@dataclass
class Energies:
    """The terms' values (summed over processes), by series name."""

    values: dict[str, float]
    kinds: dict[str, str]

    def _sum(self, kind: str) -> float:
        return sum(v for name, v in self.values.items() if self.kinds[name] == kind)

    @property
    def total(self) -> float:
        """What the bodies hold now: the stored terms."""
        return self._sum(STORED)

    @property
    def work(self) -> float:
        """The work done on the bodies since t = 0."""
        return self._sum(WORK)

    @property
    def dissipated(self) -> float:
        """The energy the bodies dissipated since t = 0 (plastic flow)."""
        return self._sum(DISSIPATED)

    @property
    def balance(self) -> float:
        return self.total + self.dissipated - self.work

    @property
    def supplied_work(self) -> float:
        """The work terms that put energy in (their positive parts)."""
        return sum(max(v, 0.0) for name, v in self.values.items() if self.kinds[name] == WORK)

    @property
    def kinetic(self) -> float:
        return self.values["kinetic_energy"]

    @property
    def strain(self) -> float:
        return self.values["strain_energy"]

    def __getattr__(self, name: str) -> float:   # e.external_work, e.damping_work, ...
        values = self.__dict__.get("values", {})
        if name in values:
            return values[name]
        if name.endswith("_work") or name.endswith("_energy"):   # (plastic_work too)
            return 0.0   # a term this scene does not have
        raise AttributeError(name)


def measure(sim) -> Energies:
    """Every term of the simulation's scene, summed over the processes."""
    chosen = terms(sim.scene)
    totals = sim.domain.sum([float(t.local(sim)) for t in chosen])
    return Energies({t.name: float(v) for t, v in zip(chosen, totals)}, {t.name: t.kind for t in chosen})


def series_row(energies: Energies, initial: float) -> dict[str, float]:
    """The series columns of one row: every term, the stored total, the balance and its error."""
    return {**energies.values, "total_energy": energies.total, "energy_balance": energies.balance,
            "energy_error": energies.balance - initial}
