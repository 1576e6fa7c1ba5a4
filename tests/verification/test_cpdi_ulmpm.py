"""CPDI-R4 in ULMPM (review 3.6-3.7; spec B.5, E5/E6 with CPDI, E28).

- E5/E6 (solver/manufactured.py): the unit segment and square, G = 0.05, one period.
  With hats ULMPM does not converge (docs/benchmarks.md: e2 grows as h falls) and
  uGIMP reaches order 1; CPDI-R4's weights follow the deformed domains, and
  benchmarks/convergence.py measures local orders 1.98-2.00 (E5, h = 1/8 to 1/128)
  and 1.75-1.96 (E6, 1/4 to 1/32). Asserted: the fitted order over 1/8, 1/16, 1/32
  at least 1.8, the oracle the spec sets for order-2 methods (E5, E6).
- E28: a bar pulled apart at 2 m/s stretches its particles' domains beyond the
  cells next to their own; the stencil grows with them (solver/shape/kernels/cpdi.py)
  and the run completes (the review's holes, [R] 3.7, remain: the accuracy that
  costs is measured on E7).
- E7 (solver/manufactured.py): the vortex twists each domain up to 7x; with 2
  particles per cell (h / 2 at t = 0) the domains span more than 3 cells at the
  peak. Asserted: cpdi_q4 and cpdi_r4 run to the end with e2 below TLMPM with hats
  at the same h and particles per cell (the issue's criterion; a comparison of two
  runs, no tolerance): to t = 0.3 in the default suite, to t = 1 marked slow.
"""
import pytest

from mpm_cases import run_scene

from solver.manufactured import Options, cube_displacement, cube_scene
from solver.norms import errors_of_result, fitted_order, observed_orders

LEVELS = [1 / 8, 1 / 16, 1 / 32]
FLIP = {1: 1.0, 2: 0.99}   # the source's FLIP shares for E5 and E6 (docs/benchmarks.md)


def e2_over_levels(run_case, dim):
    errors = []
    for h in LEVELS:
        options = Options(formulation="ulmpm", shape="cpdi_r4", flip_ratio=FLIP[dim])
        case = run_case(cube_scene(dim, h, 0.05, options), f"d{dim}-h{round(1 / h)}")
        assert case.result.status == "complete", case.result.message
        errors.append(errors_of_result(case.path, lambda X, t: cube_displacement(X, t, 0.05)).e2)
    return errors


def test_e5_segment_ulmpm_cpdi_converges_with_order_two(run_case):
    e2 = e2_over_levels(run_case, 1)
    assert fitted_order(LEVELS, e2) >= 1.8, (e2, observed_orders(LEVELS, e2))


@pytest.mark.slow
def test_e6_square_ulmpm_cpdi_converges_with_order_two(run_case):
    e2 = e2_over_levels(run_case, 2)
    assert fitted_order(LEVELS, e2) >= 1.8, (e2, observed_orders(LEVELS, e2))


def stretched_bar(particles_per_cell: int) -> dict:
    """A soft bar 0.4 x 0.1 whose ends are pulled apart at 1 m/s each (velocity conditions
    on the nodes beyond x = -+0.19), h = 0.05."""
    pull = [{"type": "velocity", "where": {"type": "box", "lower": [-1.0, -0.2], "upper": [-0.19, 0.2]},
             "velocity": [-1.0, None]},
            {"type": "velocity", "where": {"type": "box", "lower": [0.19, -0.2], "upper": [1.0, 0.2]},
             "velocity": [1.0, None]}]
    return {"version": 1, "name": "E28: a bar stretched until CPDI's domains outgrow the cells next to theirs", "dimension": 2,
            "method": {"shape_function": "cpdi_r4", "transfer": "flip", "scheme": "musl"},
            "grid": {"lower": [-1.0, -0.2], "upper": [1.0, 0.2], "cell_size": 0.05},
            "materials": {"m": {"model": "neo_hookean", "density": 1000, "youngs_modulus": 10.0,
                                "poisson_ratio": 0.3}},
            "bodies": [{"name": "bar", "material": "m", "particles_per_cell": particles_per_cell,
                        "geometry": {"type": "box", "lower": [-0.2, -0.05], "upper": [0.2, 0.05]}}],
            "boundary_conditions": pull,
            "time": {"end": 0.15, "dt": 0.0005},
            "output": {"frames": 2, "fields": ["position", "particle_domain"]}}


def test_e28_a_domain_stretched_beyond_the_neighbouring_cells_widens_the_stencil_and_the_run_completes(run_case):
    """One particle per cell: the domains (h wide at t = 0) are stretched over more than 2
    cells before t = 0.15, beyond the cells next to the particle's own (where the run used
    to stop); the stencil grows with them and the run reaches the end."""
    import numpy as np
    case = run_case(stretched_bar(1), "ppc1")
    assert case.result.status == "complete", case.result.message
    corners = case.frame(-1)["fields"]["particle_domain"].reshape(-1, 4, 2)
    extent = (corners.max(axis=1) - corners.min(axis=1)) / 0.05
    assert extent[:, 0].max() > 2.0, extent.max(axis=0)


def vortex_errors(h: float, shape: str, end: float) -> dict:
    """e2 of ULMPM with `shape` and of TLMPM with hats on the E7 vortex to `end`, both 2
    particles per cell (TLMPM's own setting in the E7 table of docs/benchmarks.md), pure
    FLIP as [R] 6, three frames; and the largest extent of a CPDI domain, in cells."""
    import tempfile
    from pathlib import Path

    import numpy as np

    from solver.manufactured import R_OUT, vortex_displacement, vortex_scene
    cpdi = vortex_scene(h, Options(formulation="ulmpm", shape=shape, ppc=2, flip_ratio=1.0, frames=3), end=end)
    cpdi["grid"].update(lower=[-R_OUT - 2 * h] * 2, upper=[R_OUT + 2 * h] * 2)   # room for ULMPM's particles
    cpdi["output"]["fields"].append("particle_domain")
    hats = vortex_scene(h, Options(formulation="tlmpm", shape="linear", ppc=2, flip_ratio=1.0, frames=3), end=end)
    out, extent = {}, 0.0
    with tempfile.TemporaryDirectory() as folder:
        for name, scene in (("cpdi", cpdi), ("hats", hats)):
            case = run_scene(scene, Path(folder) / name)
            assert case.result.status == "complete" and case.result.time == pytest.approx(end), case.result.message
            out[name] = errors_of_result(case.path, vortex_displacement).e2
            if name == "cpdi":
                for index in range(3):
                    corners = case.frame(index)["fields"]["particle_domain"].reshape(-1, 4, 2)
                    extent = max(extent, float(np.max(corners.max(axis=1) - corners.min(axis=1))) / h)
    return {**out, "extent": extent}


@pytest.mark.parametrize("shape", ["cpdi_q4", "cpdi_r4"])
def test_e7_vortex_stretching_the_domains_over_two_cells_runs_below_tlmpm_hats(shape):
    """h = 0.05 to t = 0.3: the domains reach 2 cells by t = 0.13 (where the 4-node stencil
    stopped cpdi_q4) and more by t = 0.3."""
    e = vortex_errors(0.05, shape, 0.3)
    assert e["extent"] > 2.0, e
    assert e["cpdi"] < e["hats"], e


@pytest.mark.slow
@pytest.mark.parametrize("shape", ["cpdi_q4", "cpdi_r4"])
def test_e7_vortex_at_two_particles_per_cell_reaches_t1_below_tlmpm_hats(shape):
    """The issue's E7 criterion: h = 0.05, 2 particles per cell, to t = 1 (the domains span
    more than 3 cells at the peak, t = 0.5)."""
    e = vortex_errors(0.05, shape, 1.0)
    assert e["extent"] > 3.0, e
    assert e["cpdi"] < e["hats"], e
