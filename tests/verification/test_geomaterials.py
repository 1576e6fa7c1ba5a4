"""Drucker-Prager and Mohr-Coulomb on single material points (no grid, see
material_point.py); tension positive, sigma_1 >= sigma_2 >= sigma_3.

References (closed forms of the models, de Souza Neto, Peric & Owen 2008, ch. 8):
- triaxial compression (sigma_1 = sigma_2 = -p0) and extension (sigma_2 = sigma_3 = -p0):
  the axial stress at failure solves Phi = 0 for the model (Mohr-Coulomb,
  and each of Drucker-Prager's three fits of eq. 8.88);
- the return mapping: the returned stress lies on the surface and the plastic strain
  increment follows the potential (dilation angle);
- the oedometer (zero lateral strain): sigma_h = nu / (1 - nu) sigma_v while elastic,
  then on the active Rankine line sigma_h = K_a sigma_v - 2 c sqrt(K_a) (compression
  positive, K_a = (1 - sin phi) / (1 + sin phi)), where the cone meets it.
The models are perfectly plastic, so these hold to round-off: the tolerances are a few
hundred ulps of the stress scale.
"""
import math

import numpy as np
import pytest

from material_point import MaterialPoint

E, NU, RHO = 1e7, 0.2, 2000.0
K, G = E / (3 * (1 - 2 * NU)), E / (2 * (1 + NU))
PHI, PSI, C = 30.0, 10.0, 1e4
SOIL = {"density": RHO, "youngs_modulus": E, "poisson_ratio": NU, "friction_angle": PHI, "cohesion": C,
        "dilation_angle": PSI}
MODELS = [{"model": "mohr_coulomb"}, {"model": "drucker_prager", "fit": "compression"},
          {"model": "drucker_prager", "fit": "extension"}, {"model": "drucker_prager", "fit": "plane_strain"}]
ROUND_OFF = 1e-12     # relative to the stress scale (about 1e5 Pa here: 1e-7 Pa)


def soil(extra, **changes):
    return {**SOIL, **extra, **changes}


def phi_value(config, sigma):
    """The model's yield function at a 3x3 stress."""
    s1, s2, s3 = np.sort(np.linalg.eigvalsh(sigma))[::-1]
    sp, cp = math.sin(math.radians(PHI)), math.cos(math.radians(PHI))
    if config["model"] == "mohr_coulomb":
        return (s1 - s3) + (s1 + s3) * sp - 2 * C * cp
    eta, xi = cone(config["fit"], PHI, config.get("dilation_angle", PSI))
    m = np.trace(sigma) / 3
    dev = sigma - m * np.eye(3)
    return math.sqrt(0.5 * np.sum(dev * dev)) + eta * m - xi * C


def cone(fit, angle, dilation=None):
    """de Souza Neto eq. 8.88, written out again here (not taken from the solver). In plane
    strain with a dilation angle below phi, the cone through Mohr-Coulomb's plane-strain
    collapse (no plastic strain out of the plane: s_zz = -2 eta_bar sqrt(J2) / 3), solved
    for eta by bisection from t (1 - eta eta_bar / 3) / r + eta m = xi c, with xi = cot(phi)
    eta (the apexes meet) and t + sin(phi) m = c cos(phi)."""
    s, t = math.sin(math.radians(angle)), math.tan(math.radians(angle))
    if fit == "plane_strain" and dilation is not None and dilation != angle:
        eta_bar = cone("plane_strain", dilation)[0]
        r = math.sqrt(1 - eta_bar**2 / 3)
        low, high = 0.0, 2.0   # the slope of t against -m: (eta / r') = sin(phi), r' = (1 - eta eta_bar / 3) / r
        for _ in range(200):
            eta = 0.5 * (low + high)
            low, high = (eta, high) if eta * r / (1 - eta * eta_bar / 3) < s else (low, eta)
        return eta, eta / t
    if fit == "plane_strain":
        return 3 * t / math.sqrt(9 + 12 * t * t), 3 / math.sqrt(9 + 12 * t * t)
    d = math.sqrt(3) * (3 - s if fit == "compression" else 3 + s)
    return 6 * s / d, 6 * math.cos(math.radians(angle)) / d


def axial_failure_stress(config, p0, compression):
    """sigma_a at failure with the lateral stresses at -p0."""
    sp, cp = math.sin(math.radians(PHI)), math.cos(math.radians(PHI))
    if config["model"] == "mohr_coulomb":
        if compression:     # s1 = s2 = -p0, s3 = sigma_a
            return -(2 * C * cp + p0 * (1 + sp)) / (1 - sp)
        return (2 * C * cp - p0 * (1 - sp)) / (1 + sp)   # s1 = sigma_a, s2 = s3 = -p0
    eta, xi = cone(config["fit"], PHI, config.get("dilation_angle", PSI))
    sign = -1.0 if compression else 1.0    # sqrt(J2) = sign (sigma_a + p0) / sqrt(3)
    return (xi * C - sign * p0 / math.sqrt(3) + 2 * eta * p0 / 3) / (sign / math.sqrt(3) + eta / 3)


@pytest.mark.parametrize("extra", MODELS, ids=lambda e: e.get("fit", e["model"]))
@pytest.mark.parametrize("compression", [True, False], ids=["compression", "extension"])
def test_triaxial_failure_stress(extra, compression):
    """Mixed control: lateral stresses held at -p0, axial strain driven well past failure;
    the axial stress reaches the model's failure stress and stays there."""
    p0 = 1e5
    point = MaterialPoint(soil(extra), 3, stress=-p0 * np.eye(3))
    rate, dt = (-0.05 if compression else 0.05), 4e-3
    for _ in range(250):       # 5 % axial strain; failure at 2.3 % (compression), 1 % (extension)
        point.mixed_step(np.diag([0.0, 0.0, rate]), dt, held=(0, 1), target=-p0, stiffness=2 * K + 2 * G / 3)
    expected = axial_failure_stress(extra, p0, compression)
    assert point.state("yield_state") > 0
    assert point.stress[2, 2] == pytest.approx(expected, rel=ROUND_OFF, abs=ROUND_OFF * p0)
    assert abs(phi_value(extra, point.stress)) < ROUND_OFF * p0


def test_drucker_prager_fits_match_mohr_coulomb_on_their_meridian():
    """The compression cone meets Mohr-Coulomb in triaxial compression, the extension cone
    in extension (a check of eq. 8.88 itself, through the closed forms above)."""
    mc = {"model": "mohr_coulomb"}
    for fit, compression in (("compression", True), ("extension", False)):
        dp = {"model": "drucker_prager", "fit": fit}
        assert axial_failure_stress(dp, 1e5, compression) == pytest.approx(
            axial_failure_stress(mc, 1e5, compression), rel=1e-14)


@pytest.mark.parametrize("model,dilation", [("mohr_coulomb", 0.0), ("drucker_prager", 0.0),
                                           ("drucker_prager", PSI), ("drucker_prager", PHI)])
def test_plane_strain_collapse_is_mohr_coulombs(model, dilation):
    """Biaxial plane strain (2D): sigma_xx held at -p0, sigma_yy driven far past failure,
    sigma_zz free. At collapse the out-of-plane stress has stopped changing (no plastic
    strain out of the plane), and sigma_yy is Mohr-Coulomb's, -(2 c cos(phi) + p0 (1 +
    sin(phi))) / (1 - sin(phi)), for Drucker-Prager's plane-strain fit at any dilation angle.
    Drucker-Prager's sigma_zz approaches its limit exponentially in the strain (2e-9 of the
    stress left at 40 % axial strain without dilation): at 80 % it is there to round-off."""
    p0 = 1e5
    config = soil({"model": model, "fit": "plane_strain"} if model == "drucker_prager" else {"model": model},
                  dilation_angle=dilation)
    point = MaterialPoint(config, 2, stress=-p0 * np.eye(3))
    for _ in range(2000):
        point.mixed_step(np.diag([0.0, -0.1]), 4e-3, held=(0,), target=-p0, stiffness=K + 4 * G / 3)
    sp, cp = math.sin(math.radians(PHI)), math.cos(math.radians(PHI))
    expected = -(2 * C * cp + p0 * (1 + sp)) / (1 - sp)
    assert point.stress[1, 1] == pytest.approx(expected, rel=ROUND_OFF)


def random_plastic_steps(config, dim=3, count=300, seed=1):
    """(stress before, stress after, strain increment, yield state) of plastic steps from
    random stresses inside the surface, with random symmetric strain increments."""
    rng = np.random.default_rng(seed)
    point = MaterialPoint(config, dim)
    steps = []
    while len(steps) < count:
        start = -1e5 * np.eye(3) + 4e4 * _symmetric(rng)
        if dim == 2:
            start[0, 2] = start[2, 0] = start[1, 2] = start[2, 1] = 0.0
        if phi_value(config, start) >= 0:
            continue
        point.p.stress[0] = start
        point.p.F[0] = np.eye(dim)
        strain = 0.03 * _symmetric(rng)[:dim, :dim]
        point.step(strain, 1.0)          # dt = 1: the strain increment is L
        if point.state("yield_state") > 0:
            steps.append((start, point.stress.copy(), strain, point.state("yield_state")))
    return steps


def _symmetric(rng):
    a = rng.standard_normal((3, 3))
    return 0.5 * (a + a.T)


def plastic_strain(before, after, strain):
    """de_p = de - C^-1 (sigma_after - sigma_before) (no spin: L symmetric)."""
    full = np.zeros((3, 3))
    full[:strain.shape[0], :strain.shape[0]] = strain
    ds = after - before
    return full - (ds - np.trace(ds) / 3 * np.eye(3)) / (2 * G) - np.trace(ds) / (9 * K) * np.eye(3)


@pytest.mark.parametrize("extra", MODELS, ids=lambda e: e.get("fit", e["model"]))
@pytest.mark.parametrize("dim", [2, 3])
def test_return_lands_on_the_surface(extra, dim):
    steps = random_plastic_steps(soil(extra), dim)
    states = {state for *_, state in steps}
    assert 1 in states and 3 in states        # the smooth part and the apex were both exercised
    if extra["model"] == "mohr_coulomb":
        assert 2 in states                    # and the edges
    for _, after, _, _ in steps:
        assert abs(phi_value(extra, after)) < ROUND_OFF * 1e5


def test_drucker_prager_flow_follows_the_dilation_angle():
    """On the cone de_p = dg (s / (2 sqrt(J2)) + eta_bar / 3 I): deviatoric part along s,
    tr(de_p) / |dev de_p| = sqrt(2) eta_bar."""
    config = soil({"model": "drucker_prager", "fit": "compression"})
    eta_bar = cone("compression", PSI)[0]
    for before, after, strain, state in random_plastic_steps(config):
        if state != 1:
            continue
        ep = plastic_strain(before, after, strain)
        dev = ep - np.trace(ep) / 3 * np.eye(3)
        s = after - np.trace(after) / 3 * np.eye(3)
        assert np.linalg.norm(dev / np.linalg.norm(dev) - s / np.linalg.norm(s)) < 1e-9
        assert np.trace(ep) / np.linalg.norm(dev) == pytest.approx(math.sqrt(2) * eta_bar, rel=1e-9)


def test_mohr_coulomb_flow_follows_the_dilation_angle():
    """On a plane or an edge de_p = sum dg_i n_i with every n_i a permutation of
    (1 + sin psi, 0, -(1 - sin psi)) and dg_i >= 0: the principal plastic strains sum to
    positive/negative parts in the ratio -(1 + sin psi) / (1 - sin psi); on the main
    plane the middle one is zero. Coaxial with the stress."""
    sp = math.sin(math.radians(PSI))
    seen = set()
    for before, after, strain, state in random_plastic_steps(soil({"model": "mohr_coulomb"})):
        if state not in (1, 2):
            continue
        seen.add(state)
        ep = plastic_strain(before, after, strain)
        values, vectors = np.linalg.eigh(ep)
        scale = np.abs(values).max()
        positive, negative = values[values > 0].sum(), values[values < 0].sum()
        assert positive / negative == pytest.approx(-(1 + sp) / (1 - sp), rel=1e-8)
        commutator = ep @ after - after @ ep
        assert np.abs(commutator).max() < 1e-8 * scale * 1e5
        if state == 1:
            assert abs(np.median(values)) < 1e-8 * scale
    assert seen == {1, 2}


@pytest.mark.parametrize("model", ["mohr_coulomb", "drucker_prager"])
def test_apex_and_tension_cutoff(model):
    """Hydrostatic stretching ends at the apex c cot(phi), or at the cut-off T below it."""
    apex = C / math.tan(math.radians(PHI))
    for cutoff, expected, state in ((None, apex, 3), (0.25 * apex, 0.25 * apex, 4)):
        point = MaterialPoint(soil({"model": model}, tension_cutoff=cutoff), 3)
        for _ in range(50):
            point.step(0.01 * np.eye(3), 1.0)
        assert np.allclose(point.stress, expected * np.eye(3), rtol=ROUND_OFF, atol=ROUND_OFF * apex)
        assert point.state("yield_state") == state
    # the cut-off also caps a sheared state: mean stress T, deviator back on the surface
    point = MaterialPoint(soil({"model": model}, tension_cutoff=0.25 * apex), 3)
    for _ in range(50):
        point.step(np.diag([0.02, 0.01, 0.005]), 1.0)
    assert np.trace(point.stress) / 3 == pytest.approx(0.25 * apex, rel=ROUND_OFF)
    extra = {"model": model, "fit": "compression"}
    assert abs(phi_value(extra, point.stress)) < ROUND_OFF * apex


def oedometer(config, dim, steps=600):
    """(sigma_v, sigma_h, yield state) per step of confined compression, compression positive."""
    point = MaterialPoint(config, dim)
    axis = dim - 1
    rate = np.zeros((dim, dim))
    rate[axis, axis] = -0.05
    out = []
    for _ in range(steps):
        point.step(rate, 1e-3)
        out.append((-point.stress[axis, axis], -point.stress[0, 0], point.state("yield_state")))
    return np.array(out)


@pytest.mark.parametrize("model", ["mohr_coulomb", "drucker_prager"])
@pytest.mark.parametrize("dim", [2, 3])
def test_oedometer(model, dim):
    """Elastic ratio nu / (1 - nu) up to the predicted sigma_v*, the Rankine line after it."""
    path = oedometer(soil({"model": model}), dim)
    ka = (1 - math.sin(math.radians(PHI))) / (1 + math.sin(math.radians(PHI)))
    k_elastic = NU / (1 - NU)
    onset = 2 * C * math.sqrt(ka) / (ka - k_elastic)
    sv, sh, state = path.T
    elastic, plastic = state == 0, state > 0
    assert np.all(sv[elastic] < onset * (1 + 1e-12)) and np.all(sv[plastic] > onset * (1 - 1e-12))
    assert plastic.sum() > 200 and elastic.sum() > 200
    assert np.allclose(sh[elastic] / sv[elastic], k_elastic, rtol=1e-12)
    assert np.allclose(sh[plastic], ka * sv[plastic] - 2 * C * math.sqrt(ka), rtol=0, atol=ROUND_OFF * sv.max())


@pytest.mark.parametrize("model", ["mohr_coulomb", "drucker_prager"])
def test_rigid_rotation_turns_the_stress_and_creates_none(model):
    """Confined compression onto the yield surface, then a rigid spin by 90 degrees about x
    (L = W, the objective rate of the other plastic models): sigma = R sigma0 R^T. The
    Hughes-Winget rotation turns by 2 atan(w dt / 2) per step, short by theta (w dt)^2 / 12
    = 3.2e-7 rad after 1000 steps: 1e-6 of the stress bounds the components' error."""
    point = MaterialPoint(soil({"model": model}), 3)
    for _ in range(600):                              # past the onset at 139 kPa
        point.step(np.diag([0.0, 0.0, -0.05]), 1e-3)
    assert point.state("yield_state") > 0
    point.rigid_volume = True
    sigma0, eps0 = point.stress.copy(), point.state("plastic_strain")
    steps, dt = 1000, 1e-6
    w = math.pi / 2 / (steps * dt)
    spin = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, -w], [0.0, w, 0.0]])
    for _ in range(steps):
        point.step(spin, dt)
    R = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])
    np.testing.assert_allclose(point.stress, R @ sigma0 @ R.T, rtol=0, atol=1e-6 * np.abs(sigma0).max())
    assert point.state("plastic_strain") == pytest.approx(eps0, rel=1e-9)


def test_strength_parameters_are_checked_at_their_paths():
    from solver.scene import SceneError
    from solver.scene_checks import load_scene
    scene = {"dimension": 2, "grid": {"lower": [0, 0], "upper": [1, 1], "cell_size": 0.1},
             "materials": {"sand": soil({"model": "drucker_prager"}, dilation_angle=40.0),
                           "clay": soil({"model": "mohr_coulomb"}, friction_angle=0.0, dilation_angle=0.0, cohesion=0.0)},
             "bodies": [{"name": "b", "material": "sand", "geometry": {"type": "box", "lower": [0, 0], "upper": [1, 1]}}],
             "time": {"end": 1.0}}
    with pytest.raises(SceneError) as error:
        load_scene(scene)
    message = str(error.value)
    assert "materials.sand.dilation_angle: must be <= friction_angle (30)" in message
    assert "materials.clay.cohesion: must be > 0 when friction_angle is 0" in message
