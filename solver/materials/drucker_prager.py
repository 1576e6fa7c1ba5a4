"""The `drucker_prager` material: perfectly plastic Drucker-Prager with a non-associated
flow rule (dilation angle), a tension cut-off and the apex return (de Souza Neto, Peric
& Owen 2008, sec. 8.3; the return mapping is solver/materials/kernels/drucker_prager.py).

`FrictionalMaterial` holds the keys it shares with `mohr_coulomb` (angles in degrees)."""

import math
from typing import Annotated, Literal

from pydantic import Field, Strict, model_validator

from solver.materials import plastic_work
from solver.materials.registry import MaterialType, StateVariable
from solver.schema import ElasticMaterial, NonNegative, fmt, problems_at

Angle = Annotated[float, Strict(), Field(ge=0, lt=90)]   # degrees

# Output fields of both frictional models. yield_state: 0 elastic, 1 on the smooth
# yield surface (a plane of Mohr-Coulomb), 2 on an edge of Mohr-Coulomb, 3 at the apex,
# 4 on the tension cut-off (the value of the last step).
FRICTIONAL_STATE = (StateVariable("plastic_strain", output=True),   # accumulated sqrt(2/3 de_p : de_p)
                    StateVariable("yield_state", output=True), plastic_work.STATE)
ELASTIC, SURFACE, EDGE, APEX, TENSION = 0, 1, 2, 3, 4


class FrictionalMaterial(ElasticMaterial):
    """Elastic constants plus the Mohr-Coulomb strength parameters."""

    friction_angle: Angle          # phi
    cohesion: NonNegative = 0.0    # c (a stress)
    dilation_angle: Angle = 0.0    # psi <= phi; psi = phi is associated flow
    tension_cutoff: NonNegative | None = None   # largest mean stress tr(sigma)/3; None: the cone's apex

    @model_validator(mode="after")
    def _strength(self) -> "FrictionalMaterial":
        problems = []
        if self.dilation_angle > self.friction_angle:
            problems.append(("dilation_angle", f"must be <= friction_angle ({fmt(self.friction_angle)}): "
                                               "a dilation angle above the friction angle creates energy"))
        if self.friction_angle == 0 and self.cohesion == 0:
            problems.append(("cohesion", "must be > 0 when friction_angle is 0 (the soil would have no strength)"))
        if problems:
            raise problems_at(problems)
        return self

    def apex_mean_stress(self) -> float:
        """c cot(phi): the largest mean stress the cone allows (infinite for phi = 0)."""
        phi = math.radians(self.friction_angle)
        return math.inf if phi == 0 else self.cohesion / math.tan(phi)

    def default_k0(self) -> float:
        """Jaky's earth pressure coefficient at rest, 1 - sin(phi)."""
        return 1.0 - math.sin(math.radians(self.friction_angle))


class DruckerPrager(FrictionalMaterial):
    model: Literal["drucker_prager"]
    # Which Mohr-Coulomb meridian the cone passes through (de Souza Neto eq. 8.88):
    # "compression" (outer cone), "extension" (inner cone) or "plane_strain" (the same
    # plane-strain collapse loads as Mohr-Coulomb, for its dilation angle: `strength`).
    fit: Literal["compression", "extension", "plane_strain"] = "compression"

    def cone(self, angle_degrees: float) -> tuple[float, float]:
        """(eta, xi) of sqrt(J2) + eta tr(sigma)/3 - xi c for this fit and angle, as eq. 8.88
        gives them (in plane strain: for associated flow). The potential's eta_bar is the eta
        of the dilation angle: in plane strain the plastic volume change is then sin(psi) times
        the in-plane shear, as in Mohr-Coulomb."""
        s, t = math.sin(math.radians(angle_degrees)), math.tan(math.radians(angle_degrees))
        if self.fit == "plane_strain":
            root = math.sqrt(9.0 + 12.0 * t * t)
            return 3.0 * t / root, 3.0 / root
        denominator = math.sqrt(3.0) * (3.0 - s if self.fit == "compression" else 3.0 + s)
        return 6.0 * s / denominator, 6.0 * math.cos(math.radians(angle_degrees)) / denominator

    def strength(self) -> tuple[float, float, float]:
        """(eta, xi, eta_bar): the yield cone and the potential's slope.

        In plane strain the cone that collapses where Mohr-Coulomb does depends on the flow.
        At collapse no plastic strain goes out of the plane, so s_zz = -2 eta_bar sqrt(J2) / 3;
        with t = (sigma_1 - sigma_3) / 2 and m = (sigma_1 + sigma_3) / 2 in the plane,
        sqrt(J2) = t / r and tr(sigma)/3 = m - eta_bar sqrt(J2) / 3, r = sqrt(1 - eta_bar^2 / 3).
        The cone then reads t (1 - eta eta_bar / 3) / r + eta m = xi c: Mohr-Coulomb's
        t + sin(phi) m = c cos(phi) for the eta and xi below. Associated flow (eta_bar = eta)
        gives eq. 8.88 again; no dilation gives eta = sin(phi), xi = cos(phi)."""
        eta_bar = self.cone(self.dilation_angle)[0]
        if self.fit != "plane_strain":
            return (*self.cone(self.friction_angle), eta_bar)
        s, c = math.sin(math.radians(self.friction_angle)), math.cos(math.radians(self.friction_angle))
        r = math.sqrt(1.0 - eta_bar * eta_bar / 3.0)
        eta = s / (r + s * eta_bar / 3.0)
        return eta, c * (1.0 - eta * eta_bar / 3.0) / r, eta_bar


MATERIAL = MaterialType(
    schema=DruckerPrager,
    solver_class="solver.materials.kernels.drucker_prager:DruckerPrager",
    state=FRICTIONAL_STATE,
)
