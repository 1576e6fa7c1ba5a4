"""The units a scene's numbers are in, as labels for plots (scene key `units`).

The solver has no units: it computes in whatever consistent set the scene's
numbers are given in (docs/units.md). `units` only names that set, so that
previews, the dashboard's viewer and animations can label axes and colour bars
("x [mm]", "von_mises [MPa]"). Nothing is converted.
"""
from __future__ import annotations

from typing import Annotated, Any

from pydantic import Field, StringConstraints

from solver.schema import SceneModel

Label = Annotated[str, StringConstraints(min_length=1, max_length=24, pattern=r"^[^\x00-\x1f]+$")]

# The physical quantity of each output field; fields not listed here (strains,
# damage, the deformation gradient, ids) are shown without a unit.
FIELD_QUANTITIES = {
    "position": "length",
    "velocity": "velocity",
    "velocity_magnitude": "velocity",
    "stress": "stress",
    "pressure": "stress",
    "pressure_smoothed": "stress",
    "von_mises": "stress",
    "strain_energy_density": "stress",  # energy per volume
    "mass": "mass",
    "volume": "volume",
    "density": "density",
    "temperature": "temperature",
    "internal_energy": "specific_energy",
}


class Units(SceneModel):
    """Labels of the scene's base units; the derived ones are built from them unless given."""
    length: Label = Field(description='e.g. "m", "mm"')
    time: Label = Field(description='e.g. "s", "ms"')
    mass: Label = Field(description='e.g. "kg", "g", "t"')
    stress: Label | None = Field(None, description='e.g. "Pa", "MPa"; default mass/(length time^2)')
    energy: Label | None = Field(None, description='e.g. "J", "mJ"; default mass length^2/time^2')
    temperature: Label | None = Field(None, description='e.g. "K"')

    def of(self, quantity: str) -> str | None:
        """The label of a quantity (`length`, `velocity`, `stress`, ...), None when unknown."""
        length, time, mass = self.length, self.time, self.mass
        derived = {
            "length": length, "time": time, "mass": mass,
            "velocity": f"{length}/{time}",
            "volume": f"{length}³",
            "density": f"{mass}/{length}³",
            "stress": self.stress or f"{mass}/({length}·{time}²)",
            "energy": self.energy or f"{mass}·{length}²/{time}²",
            "specific_energy": f"{length}²/{time}²",
            "temperature": self.temperature,
        }
        return derived.get(quantity)


def unit_of_field(units: dict[str, Any] | None, field: str) -> str | None:
    """The unit label of an output field (or a quantity name) for a scene's `units` (a dict
    as stored in a result file, or None: no labels)."""
    if not units:
        return None
    quantity = FIELD_QUANTITIES.get(field, field)
    return Units.model_validate(units).of(quantity)


def with_unit(label: str, unit: str | None) -> str:
    return f"{label} [{unit}]" if unit else label
