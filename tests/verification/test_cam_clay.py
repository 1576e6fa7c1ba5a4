"""Modified Cam-Clay on single material points (no grid, material_point.py) against the
closed forms of triaxial tests (Wood 1990, "Soil Behaviour and Critical State Soil
Mechanics", ch. 6-7; Roscoe & Burland 1968), compression positive: p' = -tr(sigma)/3,
q = sqrt(3/2 s:s), isotropic start p' = p0, p_c = p_c0 (OCR = p_c0 / p0), and a
geostatic column on the grid.

- Undrained (isochoric) triaxial compression: no volume change, so the elastic and the
  plastic volumetric strains cancel, kappa ln(p'/p0) + (lambda - kappa) ln(p_c/p_c0) = 0:
  p_c = p_c0 (p0/p')^(kappa/(lambda - kappa)), and on the yield surface
  q = M sqrt(p' (p_c - p')): the effective stress path, for normally and over-consolidated
  clay (elastic part first: p' = p0 while q < M sqrt(p0 (p_c0 - p0))). It ends at the
  critical state q = M p', p_c = 2 p'. The return keeps that relation to round-off in
  every step whatever its size (kernels/modified_cam_clay.py), so the tolerances are
  those of the Newton return (1e-13 of p_c^2 in f) and the round-off of a few hundred steps.
- Drained triaxial compression at constant cell pressure p0: the path q = 3 (p' - p0)
  (held by the mixed control to 1e-13), ending at the critical state q = M p',
  p' = 3 p0 / (3 - M), approached exponentially in the axial strain (from below for
  OCR 1 and 1.5, from above after the peak for OCR 5). On yield the stress stays on the
  ellipse of the current p_c, and the void ratio from the volume, 1 + e = (1 + e0) V/V0,
  follows e = e0 - kappa ln(p'/p0) - (lambda - kappa) ln(p_c/p_c0) (both laws integrated).
"""
import math

import numpy as np
import pytest

from material_point import MaterialPoint

LAMBDA, KAPPA, M, NU, E0, PC0, RHO = 0.2, 0.04, 1.2, 0.3, 1.0, 2.0e5, 1800.0
CLAY = {"model": "modified_cam_clay", "density": RHO, "poisson_ratio": NU, "lambda": LAMBDA, "kappa": KAPPA,
        "critical_state_slope": M, "preconsolidation_pressure": PC0, "initial_void_ratio": E0}
RETURN = 1e-10   # of p_c0: the Newton return's 1e-13 (of p_c^2 in f) and round-off, with margin
OCRS = [1.0, 1.5, 5.0]   # normally, lightly (wet side) and heavily (dry side) over-consolidated


def invariants(sigma):
    p = -np.trace(sigma) / 3
    s = sigma + p * np.eye(3)
    return p, math.sqrt(1.5 * np.sum(s * s))


def yield_value(p, q, pc):
    return q * q / M**2 + p * (p - pc)


def undrained_q(p, p0, pc0=PC0):
    """q on the undrained effective stress path at p' (on the yield surface)."""
    pc = pc0 * (p0 / p) ** (KAPPA / (LAMBDA - KAPPA))
    return M * math.sqrt(p * (pc - p))


def undrained_critical_pressure(p0, pc0=PC0):
    """p' where the undrained path meets q = M p' (p_c = 2 p')."""
    r = KAPPA / (LAMBDA - KAPPA)
    return (pc0 * p0**r / 2) ** (1 / (1 + r))


def undrained_path(ocr, rate, steps, dim=3):
    """(p', q, yield state) per step of isochoric compression (triaxial in 3D, plane strain in 2D)."""
    p0 = PC0 / ocr
    point = MaterialPoint(CLAY, dim, stress=-p0 * np.eye(3))
    L = np.diag([rate / 2, rate / 2, -rate]) if dim == 3 else np.diag([rate, -rate])
    out = []
    for _ in range(steps):
        point.step(L, 1.0)
        out.append((*invariants(point.stress), point.state("yield_state")))
    return np.array(out), point


@pytest.mark.parametrize("ocr", OCRS)
def test_undrained_triaxial_path(ocr):
    p0 = PC0 / ocr
    path, point = undrained_path(ocr, 1e-3, 400)     # 40 % axial strain
    p, q, state = path.T
    elastic, plastic = state == 0, state > 0
    first_yield = M * math.sqrt(p0 * (PC0 - p0))
    if ocr > 1:   # elastic first: p' stays p0 (no volume change), up to the ellipse
        assert elastic.sum() > 5
        np.testing.assert_allclose(p[elastic], p0, rtol=1e-14)
        assert np.all(q[elastic] <= first_yield * (1 + 1e-12))
    else:
        assert elastic.sum() == 0
    closed = np.array([undrained_q(pp, p0) for pp in p[plastic]])
    np.testing.assert_allclose(q[plastic], closed, rtol=0, atol=RETURN * PC0)
    pcs = undrained_critical_pressure(p0)
    # 40 % strain brings the path to its end to 3e-13 (measured): 1e-9 leaves margin
    assert p[-1] == pytest.approx(pcs, rel=1e-9)
    assert q[-1] == pytest.approx(M * pcs, rel=1e-9)
    assert point.state("preconsolidation_pressure") == pytest.approx(2 * pcs, rel=1e-9)


def test_undrained_path_in_one_large_step():
    """The implicit return takes 30 % axial strain in one step onto the same path."""
    path, point = undrained_path(1.0, 0.3, 1)
    p, q, state = path[0]
    assert state == 1
    assert q == pytest.approx(undrained_q(p, PC0), abs=RETURN * PC0)
    assert abs(yield_value(p, q, point.state("preconsolidation_pressure"))) < 1e-12 * PC0**2


def test_undrained_plane_strain_path():
    """Plane strain (2D) isochoric compression: another Lode angle, the same p'-q path
    (Cam-Clay's surface depends on p' and q only)."""
    path, _ = undrained_path(1.0, 1e-3, 300, dim=2)
    p, q, state = path.T
    assert np.all(state > 0)
    closed = np.array([undrained_q(pp, PC0) for pp in p])
    np.testing.assert_allclose(q, closed, rtol=0, atol=RETURN * PC0)


def drained_path(ocr, rate, strain):
    """Axial compression with the lateral stresses held at -p0: per step
    (axial strain, p', q, p_c, e from the volume, yield state) and the bound on the
    void ratio's integration error (see below)."""
    p0 = PC0 / ocr
    point = MaterialPoint(CLAY, 3, stress=-p0 * np.eye(3))
    bulk = (1 + E0) * p0 / KAPPA
    rows, bound = [], 0.0
    for n in range(1, int(round(strain / rate)) + 1):
        before = 1 + E0 if n == 1 else 1 + rows[-1][4]   # 1 + e_n
        point.mixed_step(np.diag([0.0, 0.0, -rate]), 1.0, held=(0, 1), target=-p0, stiffness=2 * bulk)
        L = point.p.L[0]
        # The model's laws give kappa dln p' + (lambda - kappa) dln p_c = (1 + e_{n+1}) tr(-L dt)
        # in each step; the volume changes by det(I + L dt): the two differ by
        # (1 + e_n) |det(I + L dt) (1 - tr(L) dt) - 1| = O((L dt)^2) a step.
        bound += before * abs(np.linalg.det(np.eye(3) + L) * (1 - np.trace(L)) - 1)
        e = (1 + E0) * point.p.volume[0] - 1
        rows.append((n * rate, *invariants(point.stress), point.state("preconsolidation_pressure"), e,
                     point.state("yield_state")))
    return np.array(rows), bound


def aitken(a, b, c):
    """The limit of a sequence converging geometrically, from three equally spaced terms."""
    return c - (c - b) ** 2 / ((c - b) - (b - a))


def check_drained(ocr, rate, strain):
    p0 = PC0 / ocr
    rows, bound = drained_path(ocr, rate, strain)
    eps, p, q, pc, e, state = rows.T
    np.testing.assert_allclose(q, 3 * (p - p0), rtol=0, atol=1e-10 * p0)
    plastic = state > 0
    assert plastic.sum() > 0.9 * len(rows)
    assert np.all(np.abs(yield_value(p[plastic], q[plastic], pc[plastic])) < 1e-12 * pc[plastic] ** 2)
    closed_e = E0 - KAPPA * np.log(p / p0) - (LAMBDA - KAPPA) * np.log(pc / PC0)
    assert np.abs(e - closed_e).max() <= bound * (1 + 1e-6) + 1e-12
    pcs = 3 * p0 / (3 - M)
    # the critical state is the discrete path's fixed point too (no plastic volume change at
    # q = M p'), approached geometrically: the extrapolation from 60, 80, 100 % strain is
    # within 2.6e-7 (p) and 6.4e-7 (q) of it at every step size tried (2e-3, 5e-4, 2.5e-4),
    # the last point within 1.4e-4
    thirds = [int(round(k * len(rows))) - 1 for k in (0.6, 0.8, 1.0)]
    assert aitken(*p[thirds]) == pytest.approx(pcs, rel=1e-6)
    assert aitken(*q[thirds]) == pytest.approx(M * pcs, rel=1e-6)
    assert abs(p[-1] / pcs - 1) < 2e-4
    if ocr >= 2.5:   # the dry side: the path crosses q = M p' and softens back to it
        assert np.max(q / p) > M * 1.05
    else:
        assert np.all(q / p < M)


@pytest.mark.parametrize("ocr", OCRS)
def test_drained_triaxial_path(ocr):
    check_drained(ocr, 2e-3, 1.0)


@pytest.mark.slow
@pytest.mark.parametrize("ocr", OCRS)
def test_drained_triaxial_path_fine_steps(ocr):
    check_drained(ocr, 2.5e-4, 1.0)


def test_random_steps_land_on_the_surface():
    """Large random strain increments (5 %) from random states inside the ellipse: every
    plastic return converges onto the ellipse of its own p_c, with p_c following the
    plastic volume change."""
    rng = np.random.default_rng(3)
    point = MaterialPoint(CLAY, 3)
    plastic = 0
    while plastic < 200:
        p0 = rng.uniform(0.05, 1.0) * PC0
        start = -p0 * np.eye(3) + 0.2 * p0 * _symmetric(rng)
        if yield_value(*invariants(start), PC0) >= 0:
            continue
        point.p.stress[0], point.p.F[0], point.p.volume[0] = start, np.eye(3), 1.0
        point.p.extra["preconsolidation_pressure"][0] = PC0
        point.step(0.05 * _symmetric(rng), 1.0)
        if point.state("yield_state") == 0:
            continue
        plastic += 1
        assert point.state("yield_state") == 1      # converged (2: not even in 64 substeps)
        pc = point.state("preconsolidation_pressure")
        assert abs(yield_value(*invariants(point.stress), pc)) < 1e-12 * pc**2


def _stress_work(point, L, steps):
    """Drive the point by L for `steps` unit steps: the work sum V_{n+1} (sigma_n +
    sigma_{n+1}) / 2 : D (the trapezoid rule, with the volume the update sees)."""
    dim = len(L)
    D = np.zeros((3, 3))
    D[:dim, :dim] = 0.5 * (np.asarray(L) + np.asarray(L).T)
    work = 0.0
    for _ in range(steps):
        before = point.stress.copy()
        point.step(L, 1.0)
        work += point.p.volume[0] * np.sum(0.5 * (before + point.stress) * D)
    return work


def _strain_energy(point):
    return float(point.model.particle_strain_energy(point.p, slice(0, 1))[0])


def test_strain_energy_is_the_work_done_on_an_elastic_path():
    """Inside the ellipse (OCR 5) a compression, a shear and a swelling back change p' by a
    factor of 2 and q from 0 to 29 kPa: the strain energy grows by the stress work. The
    volumetric parts are the same trapezoid sums, the deviatoric part exact at the step's
    G, so they agree to round-off; sigma : C^-1 : sigma / 2 at the current moduli (what this
    model's strain energy was) is off by 35 % here, since G follows p'."""
    point = MaterialPoint(CLAY, 3, stress=-PC0 / 5 * np.eye(3))
    start = _strain_energy(point)
    rate = 5e-5
    work = _stress_work(point, -rate * np.eye(3), 100)
    work += _stress_work(point, np.diag([rate / 2, rate / 2, -rate]), 100)
    work += _stress_work(point, 0.5 * rate * np.eye(3), 100)
    p, q = invariants(point.stress)
    assert 1.3 * PC0 / 5 < p and q > 2.5e4 and point.state("plastic_work") == 0
    assert _strain_energy(point) - start == pytest.approx(work, rel=1e-10)


@pytest.mark.parametrize("ocr", [1.0, 5.0])
def test_energy_of_plastic_flow_closes_at_first_order(ocr):
    """Undrained triaxial compression to 10 % axial strain: strain energy plus plastic work
    against the stress work. The backward Euler return's own dissipation, d eps_p : C :
    d eps_p / 2 a step (plastic_work.py), is the only gap: first order in the step, so it
    halves with the step (within 0.6 of the last) and is under 2 % at 100 steps."""
    gaps = []
    for steps in (100, 200, 400):
        point = MaterialPoint(CLAY, 3, stress=-PC0 / ocr * np.eye(3))
        start = _strain_energy(point)
        rate = 0.1 / steps
        work = _stress_work(point, np.diag([rate / 2, rate / 2, -rate]), steps)
        assert point.state("yield_state") == 1
        gaps.append(abs(_strain_energy(point) - start + point.state("plastic_work") - work) / abs(work))
    assert gaps[0] < 0.02
    assert gaps[1] < 0.6 * gaps[0] and gaps[2] < 0.6 * gaps[1]


def test_strain_energy_starts_at_the_work_from_rest():
    """A point compressed isotropically from rest (stress-free, below the floor first), then
    sheared at constant volume, holds the elastic work of its path: the start value of an
    initial stress (`_work_from_rest`) at the end's stress. V / a = V0 kappa / (1 + e0)
    whatever the volume, so that value is the path's work exactly; the test's trapezoid
    sum is off by about (a d eps_v)^2 / 12 = 2e-5 of it (a d eps_v = 0.015 a step)."""
    point = MaterialPoint(CLAY, 3)
    work = _stress_work(point, -1e-4 * np.eye(3), 300)
    work += _stress_work(point, np.diag([2.5e-5, 2.5e-5, -5e-5]), 80)
    p, q = invariants(point.stress)
    assert p > 20 * point.model.p_min and q > 1e4 and point.state("plastic_work") == 0
    volume = point.p.volume[0]
    a = np.array([(1 + E0) * volume / KAPPA])
    from_rest = volume * point.model._work_from_rest(np.array([p]), np.array([q]), a)[0]
    assert from_rest == pytest.approx(work, rel=1e-4)


def test_sloshing_clay_box_closes_its_energy_balance():
    """A clay box under gravity, walled on all sides, set sloshing at up to 1 m/s: it
    compacts (the plastic work grows past twice the start's kinetic energy), p' between
    0.4 and 107 kPa. Conservation is the reference: the balance error, the scheme's, is
    first order in dt (pure FLIP: no PIC damping a share of the energy every step), under
    5 % of the start's kinetic energy at cfl 0.5 and within 0.6 of that at cfl 0.25.
    With the tangent formula for the strain energy it was over 3 times that energy."""
    errors = []
    for cfl in (0.5, 0.25):
        error, plastic = sloshing_energy_error(cfl)
        assert plastic > 2
        errors.append(error)
    assert errors[0] < 0.05 and errors[1] < 0.6 * errors[0]


def sloshing_energy_error(cfl):
    """(largest abs(energy_error), plastic work at the end), both over the start's kinetic
    energy, of the sloshing box run to t = 0.5 s at `cfl`."""
    from solver import energy
    from solver.scene_checks import load_scene
    from solver.stepper import ExplicitMPM
    sim = ExplicitMPM(load_scene(sloshing_box()))
    kinetic, start = energy.measure(sim).kinetic, energy.measure(sim).balance
    worst = 0.0
    while sim.time < 0.5:
        sim.advance(sim.stable_time_step(cfl))
        worst = max(worst, abs(energy.measure(sim).balance - start))
    return worst / kinetic, energy.measure(sim).values["plastic_work"] / kinetic


def sloshing_box():
    wave = "3.14159265358979"
    return {"dimension": 2, "grid": {"lower": [0, 0], "upper": [1, 1], "cell_size": 0.05},
            "method": {"transfer": "flip", "flip_ratio": 1.0},
            "materials": {"clay": {**CLAY, "minimum_pressure": 1e3}},
            "bodies": [{"name": "box", "material": "clay",
                        "geometry": {"type": "box", "lower": [0, 0], "upper": [1, 1]},
                        "initial_stress": {"type": "geostatic"},
                        "initial_velocity": [f"sin({wave} * x) * cos({wave} * y)", f"0.5 * sin({wave} * y)"]}],
            "boundary_conditions": [{"type": "wall", "face": f, "mode": "slip"} for f in ("x-", "x+", "y-", "y+")],
            "gravity": [0, -9.81], "time": {"end": 0.5}}

def _symmetric(rng):
    a = rng.standard_normal((3, 3))
    return 0.5 * (a + a.T)


def test_wave_speed_follows_the_mean_stress():
    """The time step's wave speed is sqrt((K + 4 G / 3) / rho) of the current state,
    K = (1 + e) p' / kappa."""
    _, point = undrained_path(1.0, 1e-3, 100)
    p, _ = invariants(point.stress)
    bulk = (1 + E0) * point.p.volume[0] * p / KAPPA
    shear = 3 * bulk * (1 - 2 * NU) / (2 * (1 + NU))
    assert point.model.wave_speed == pytest.approx(math.sqrt((bulk + 4 * shear / 3) / RHO), rel=1e-12)


@pytest.mark.parametrize("axisymmetric", [False, True], ids=["plane", "axisymmetric"])
def test_geostatic_column_stays_at_rest(axisymmetric):
    """A clay column given its geostatic stress (k0 = 1 - sin(phi_cs), sin(phi_cs) = 3 M / (6 + M))
    stays at rest under gravity (test_geostatic.py says why the MPM equilibrium is exact);
    p_c starts at the ellipse through the initial stress where the given 5 kPa lies inside
    it (below 0.3 m depth), and the time step follows the stiffness of the deepest particle."""
    from solver.scene_checks import load_scene
    from solver.stability import fastest_signal
    from test_geostatic import G, column, settle
    clay = {**CLAY, "preconsolidation_pressure": 5e3}
    height = 1.0
    scene = column(height, {"type": "geostatic"}, axisymmetric, material=clay)
    sim, fastest = settle(scene)
    assert fastest < 1e-12 * math.sqrt(G * height)
    particles = sim.particles
    k0 = 1 - 3 * M / (6 + M)
    depth = height - particles.x[:, 1]
    sigma_v = RHO * G * depth
    np.testing.assert_allclose(particles.stress[:, 1, 1], -sigma_v, rtol=0, atol=1e-12 * RHO * G * height)
    np.testing.assert_allclose(particles.stress[:, 0, 0], -k0 * sigma_v, rtol=0, atol=1e-12 * RHO * G * height)
    p, q = (1 + 2 * k0) / 3 * sigma_v, (1 - k0) * sigma_v
    pc = particles.extra["preconsolidation_pressure"]
    np.testing.assert_allclose(pc, np.maximum(5e3, p + q * q / (M**2 * p)), rtol=1e-12)
    assert (pc > 5e3).sum() > 0.5 * len(pc)
    model = sim.materials[0][0]
    bulk = (1 + E0) * p.max() / KAPPA * (1 + 4 / 3 * 3 * (1 - 2 * NU) / (2 * (1 + NU)))
    assert model.wave_speed == pytest.approx(math.sqrt(bulk / RHO), rel=1e-9)
    # the limit before the run takes the box's height as the deepest depth (the deepest
    # particle is half a spacing, 1/80 of it, higher): faster by sqrt(80/79) - 1 = 0.6 %
    estimate = fastest_signal(load_scene(scene))
    assert model.wave_speed < estimate < model.wave_speed * (1 + 1e-2)


def test_scene_rules():
    """A clay body needs an initial stress; kappa < lambda."""
    from solver.scene import SceneError
    from solver.scene_checks import load_scene
    from test_geostatic import column
    scene = column(1.0, None, material={**CLAY, "kappa": 0.3})
    with pytest.raises(SceneError) as error:
        load_scene(scene)
    assert "materials.sand.kappa: must be < lambda (0.2)" in str(error.value)
    scene["materials"]["sand"]["kappa"] = KAPPA
    with pytest.raises(SceneError, match=r"bodies\[0\]\.initial_stress: required for a 'modified_cam_clay'"):
        load_scene(scene)


def test_scene_dumps_and_loads_again():
    """`lambda` (a Python keyword: the field is lambda_) is dumped under its scene name, so
    a stored scene (the service's model_dump_json) loads again."""
    import json
    from solver.scene_checks import load_scene
    from test_geostatic import column
    scene = load_scene(column(1.0, {"type": "geostatic"}, material=CLAY))
    dumped = json.loads(scene.model_dump_json())
    assert dumped["materials"]["sand"]["lambda"] == LAMBDA and "lambda_" not in dumped["materials"]["sand"]
    assert load_scene(dumped) == scene
