"""Manufactured-solution scenes (review 6.2, Appendix A; VERIFICATION_CASES E5-E7).

Each case builds an ordinary scene (so `mpm run` runs it like any other) whose
body force is the expression that makes a chosen displacement field u(X, t)
the exact solution, and gives that field for the error norms (solver/norms.py).

- `segment`: E5, the unit segment 0 <= X <= 1, u = G sin(pi X) sin(c pi t).
- `cube`: E6, the unit square/cube, u_i = G sin(pi X_i) sin(c pi t + phi_i),
  phi = (0, pi, pi), with ROLLERS on the faces (only the normal velocity is
  fixed: the source's all-components condition contradicts its own field, F17).
- `vortex`: E7, the ring 0.75 <= R <= 1.25 twisted by x = Q(g(t) h(R)) X, with
  the CORRECTED sign of the centripetal term in b_Theta (F1).

The neo-Hookean model of the solver is the one the body forces are derived for
(review B.6, plane strain in 2D, F_yy = F_zz = 1 in 1D). c = sqrt(E / rho0) is the
manufactured frequency parameter of [R], not the dilatational wave speed.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

E, NU, RHO = 1.0e7, 0.3, 1000.0          # E5/E6 material
C = math.sqrt(E / RHO)                  # 100 m/s
PERIOD = 2.0 / C                        # T = 2 pi / (c pi) = 0.02 s
VORTEX_E, VORTEX_RHO = 1.0e3, 1000.0    # E7 material (nu = 0.3)
R_IN, R_OUT, VORTEX_END = 0.75, 1.25, 1.0
CUBE_PHASE = (0.0, math.pi, math.pi)
DT_FACTOR = 0.2                         # dt = 0.2 h / c for every method ([R] 6.2.1)
# The vortex stretches the ring up to lambda = 7.2 (shear R g h' = 7.05 at t = 0.5),
# which raises the neo-Hookean wave speed in the reference configuration by about
# that factor: dt = 0.2 h / c_dil would be unstable near the peak, 1/8 of it is not.
VORTEX_DT_FACTOR = DT_FACTOR / 8
# Particles per cell and direction: 2 for every function ([R] 4.1's "at least two").
# A Bernstein element spans two cells here (solver/shape/kernels/bernstein.py), so that is 4
# per element and direction, against the 3 of VERIFICATION_CASES A.14.
PPC = 2


def lame(E_: float, nu: float) -> tuple[float, float]:
    return E_ * nu / ((1 + nu) * (1 - 2 * nu)), E_ / (2 * (1 + nu))


def _f(x: float) -> str:
    return repr(float(x))


def _method(formulation: str, shape: str, transfer: str, scheme: str, flip_ratio: float) -> dict:
    return {"formulation": formulation, "scheme": scheme, "shape_function": shape,
            "transfer": transfer, "flip_ratio": flip_ratio}


@dataclass(frozen=True)
class Options:
    """The method of a run: formulation, shape function, transfer, scheme."""

    formulation: str = "tlmpm"
    shape: str = "linear"
    transfer: str = "flip"
    scheme: str = "musl"
    flip_ratio: float = 0.99
    ppc: int = PPC
    frames: int = 21

    def method(self) -> dict:
        return _method(self.formulation, self.shape, self.transfer, self.scheme, self.flip_ratio)


# --------------------------------------------------------------------------- E5, E6

def _axis_force(i: int, dim: int, G: float) -> str:
    """b_i of E5/E6 ([R] A.8, 6.9) in X, Y, Z, t; ln J = sum_j ln F_jj (F diagonal)."""
    lam, mu = lame(E, NU)
    names = "XYZ"

    def u(j):
        return f"{_f(G)}*sin(pi*{names[j]})*sin({_f(C)}*pi*t+{_f(CUBE_PHASE[j])})"

    def F(j):
        return f"(1+pi*{_f(G)}*cos(pi*{names[j]})*sin({_f(C)}*pi*t+{_f(CUBE_PHASE[j])}))"

    lnJ = "+".join(f"log({F(j)})" for j in range(dim))
    return (f"pi**2*{u(i)}/{_f(RHO)}*({_f(lam)}/{F(i)}**2*(1-({lnJ}))"
            f"+{_f(mu)}*(1+1/{F(i)}**2)-{_f(E)})")


def cube_scene(dim: int, h: float, G: float = 0.05, options: Options = Options(),
               end: float = PERIOD) -> dict:
    """E5 (dim 1) and E6 (dim 2, 3): the unit segment/square/cube, rollers on every face."""
    names = "xyz"
    velocity = [f"{_f(math.pi * C * G * math.cos(CUBE_PHASE[a]))}*sin(pi*{names[a]})" for a in range(dim)]
    return {
        "version": 1,
        "name": f"MMS unit {'segment' if dim == 1 else 'square' if dim == 2 else 'cube'} "
                f"(E{5 if dim == 1 else 6}), G = {G:g}, h = {h:g}",
        "dimension": dim,
        "method": options.method(),
        "grid": {"lower": [0.0] * dim, "upper": [1.0] * dim, "cell_size": h},
        "materials": {"solid": {"model": "neo_hookean", "density": RHO, "youngs_modulus": E, "poisson_ratio": NU}},
        "bodies": [{"name": "solid", "material": "solid", "particles_per_cell": options.ppc,
                    "geometry": {"type": "box", "lower": [0.0] * dim, "upper": [1.0] * dim},
                    "initial_velocity": velocity}],
        # rollers: v_i = 0 on the faces X_i = 0, 1 (F17)
        "boundary_conditions": [{"type": "wall", "face": f"{names[a]}{side}", "mode": "slip"}
                                for a in range(dim) for side in "-+"],
        "body_force": [_axis_force(a, dim, G) for a in range(dim)],
        "time": {"end": end, "dt": DT_FACTOR * h / C},
        "output": {"frames": options.frames, "fields": ["position", "velocity"]},
    }


def cube_displacement(X: np.ndarray, t: float, G: float) -> np.ndarray:
    """u_i = G sin(pi X_i) sin(c pi t + phi_i)."""
    phase = np.asarray(CUBE_PHASE[:X.shape[1]])
    return G * np.sin(np.pi * X) * np.sin(C * np.pi * t + phase)


# --------------------------------------------------------------------------- E7

def _vortex_force() -> list[str]:
    """(b_1, b_2) of [R](6.17)-(6.18) with the sign of F1 corrected, G = T0 = 1.

    With A = mu/rho (3 g h' + R g h'') - R g'' h and B = mu/rho R (g h')^2 - R (g' h)^2:
    b_R = A sin(alpha) + B cos(alpha), b_Theta = -A cos(alpha) + B sin(alpha), and
    with cos(Theta) = X / R, sin(Theta) = Y / R:
    b_1 = (A (X sin + Y cos) + B (X cos - Y sin)) / R,
    b_2 = (A (Y sin - X cos) + B (X sin + Y cos)) / R.
    """
    _, mu = lame(VORTEX_E, NU)
    k = mu / VORTEX_RHO
    d = R_IN - R_OUT
    R = "sqrt(X**2+Y**2)"
    s = f"(({R}-{_f((R_IN + R_OUT) / 2)})/{_f(d)})"
    hR = f"(1-8*{s}**2+16*{s}**4)"
    dh = f"((64*{s}**3-16*{s})/{_f(d)})"
    d2h = f"((192*{s}**2-16)/{_f(d * d)})"
    g, dg, d2g = "sin(pi*t)", "(pi*cos(pi*t))", "(-pi**2*sin(pi*t))"
    alpha = f"({g}*{hR})"
    A = f"({_f(k)}*(3*{g}*{dh}+{R}*{g}*{d2h})-{R}*{d2g}*{hR})"
    B = f"({_f(k)}*{R}*({g}*{dh})**2-{R}*({dg}*{hR})**2)"
    sa, ca = f"sin({alpha})", f"cos({alpha})"
    b1 = f"({A}*(X*{sa}+Y*{ca})+{B}*(X*{ca}-Y*{sa}))/{R}"
    b2 = f"({A}*(Y*{sa}-X*{ca})+{B}*(X*{sa}+Y*{ca}))/{R}"
    return [b1, b2]


def _vortex_velocity() -> list[str]:
    """v(X, 0) = g'(0) h(R) (-Y, X) = pi h(R) (-y, x): the exact motion does not start
    at rest (g' = pi cos(pi t)), although VERIFICATION_CASES E7 lists a zero initial
    velocity; starting at rest would make the exact field no solution (an O(1) error)."""
    s = f"((sqrt(x**2+y**2)-{_f((R_IN + R_OUT) / 2)})/{_f(R_IN - R_OUT)})"
    h = f"(1-8*{s}**2+16*{s}**4)"
    return [f"-pi*{h}*y", f"pi*{h}*x"]


def vortex_scene(h: float, options: Options = Options(shape="bernstein"), end: float = VORTEX_END) -> dict:
    """E7: the ring, starting with the exact velocity, no boundary condition (R_i and R_o
    stay fixed and traction-free in the exact solution, and no node outside the ring
    carries mass), the tlmpm default grid."""
    lam, mu = lame(VORTEX_E, NU)
    c_dil = math.sqrt((lam + 2 * mu) / VORTEX_RHO)
    return {
        "version": 1,
        "name": f"Generalized vortex (E7), h = {h:g}",
        "dimension": 2,
        "method": options.method(),
        "grid": {"cell_size": h},
        "materials": {"ring": {"model": "neo_hookean", "density": VORTEX_RHO,
                               "youngs_modulus": VORTEX_E, "poisson_ratio": NU}},
        "bodies": [{"name": "ring", "material": "ring", "particles_per_cell": options.ppc,
                    "geometry": {"type": "difference", "parts": [
                        {"type": "sphere", "center": [0.0, 0.0], "radius": R_OUT},
                        {"type": "sphere", "center": [0.0, 0.0], "radius": R_IN}]},
                    "initial_velocity": _vortex_velocity()}],
        "body_force": _vortex_force(),
        "time": {"end": end, "dt": VORTEX_DT_FACTOR * h / c_dil},
        "output": {"frames": options.frames, "fields": ["position", "velocity"]},
    }


def vortex_angle(R: np.ndarray, t: float) -> np.ndarray:
    s = (R - (R_IN + R_OUT) / 2) / (R_IN - R_OUT)
    return np.sin(np.pi * t) * (1 - 8 * s**2 + 16 * s**4)


def vortex_displacement(X: np.ndarray, t: float) -> np.ndarray:
    """u = (Q(alpha) - I) X with alpha = g(t) h(R)."""
    a = vortex_angle(np.hypot(X[:, 0], X[:, 1]), t)
    c, s = np.cos(a), np.sin(a)
    return np.stack([(c - 1) * X[:, 0] - s * X[:, 1], s * X[:, 0] + (c - 1) * X[:, 1]], axis=1)


# --------------------------------------------------------------------------- examples/

def example_scenes() -> dict[str, dict]:
    """The manufactured-solution scenes of examples/ (file stem -> scene), kept equal
    to these builders by tests/unit/test_manufactured.py."""
    flip = Options(flip_ratio=1.0, frames=41)   # [R] 6 uses pure FLIP unless it says otherwise
    return {
        "mms_segment_1d": cube_scene(1, 1 / 32, 0.05, flip),
        "mms_square_2d": cube_scene(2, 1 / 16, 0.05, Options(shape="cubic_bspline", frames=41)),
        "mms_cube_3d": cube_scene(3, 1 / 8, 0.05, Options(frames=41)),
        "vortex_2d": vortex_scene(0.05, Options(shape="bernstein", frames=41)),
    }
