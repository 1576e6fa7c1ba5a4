"""E2: two elastic disks collide (review 6.1.2, Karamelo 4.1)."""
import math

import numpy as np
import pytest

from mpm_cases import centre_of_mass_velocity, run_scene

H, PPC, RHO, V = 0.05, 2, 1000.0, 0.1
EXACT_CONTACT = (0.6 * math.sqrt(2) - 0.4) / (2 * math.sqrt(2) * V)   # 1.5858 s


def two_disks(flip_ratio=1.0, end=3.5):
    disk = lambda name, c, v: {"name": name, "material": "rubber", "particles_per_cell": PPC,
                               "geometry": {"type": "sphere", "center": [c, c], "radius": 0.2},
                               "initial_velocity": [v, v]}
    return {
        "version": 1, "name": "two-disks", "dimension": 2,
        "method": {"formulation": "ulmpm", "scheme": "musl", "shape_function": "linear",
                   "transfer": "flip", "flip_ratio": flip_ratio},
        "grid": {"lower": [-0.5, -0.5], "upper": [0.5, 0.5], "cell_size": H},
        "materials": {"rubber": {"model": "linear_elastic", "density": RHO, "youngs_modulus": 1000.0,
                                 "poisson_ratio": 0.3}},
        "bodies": [disk("disk1", -0.3, V), disk("disk2", 0.3, -V)],
        "time": {"end": end, "dt": 0.001},
        "output": {"frames": 36, "fields": ["position", "velocity", "stress"]},
    }


@pytest.fixture(scope="module")
def disks(tmp_path_factory):
    return run_scene(two_disks(), tmp_path_factory.mktemp("disks"))


def test_initial_kinetic_energy_is_the_discrete_value(disks):
    # 416 particles of volume h^2 / ppc^2, each moving at |v| = sqrt(2) V
    particles = disks.result.particles
    assert particles == 416
    discrete = 0.5 * RHO * particles * (H / PPC) ** 2 * 2 * V**2
    assert disks.series()["kinetic_energy"][0] == pytest.approx(discrete, rel=1e-12)
    # and the analytical 2.513 scaled by discrete over exact disk area
    assert discrete == pytest.approx(2 * 0.5 * 2 * V**2 * RHO * math.pi * 0.2**2 * (particles * (H / PPC) ** 2)
                                     / (2 * math.pi * 0.2**2), rel=1e-12)


def first_shared_node_time(frame0, dt=0.001):
    """First time the two disks, translating rigidly, have particles in adjacent cells:
    with linear shape functions that is when they first share a grid node."""
    f = frame0["fields"]
    x1, x2 = f["position"][f["body"] == 0], f["position"][f["body"] == 1]
    for n in range(int(EXACT_CONTACT / dt) + 1):
        t = n * dt
        c1 = np.floor((x1 + V * t + 0.5) / H).astype(int)
        c2 = np.floor((x2 - V * t + 0.5) / H).astype(int)
        if np.any(np.all(np.abs(c1[:, None, :] - c2[None, :, :]) <= 1, axis=2)):
            return t
    return None


def test_no_interaction_before_the_disks_share_a_node_then_contact_before_the_exact_time(disks):
    s = disks.series()
    e0 = s["total_energy"][0]
    t_share = first_shared_node_time(disks.frame(0))
    assert t_share is not None
    before = s["time"] < t_share - 1e-9
    assert np.all(s["strain_energy"][before] < 1e-12 * e0)
    onset = s["time"][s["strain_energy"] > 1e-6 * e0][0]
    # grid contact starts about a cell early (the source reports 1.3 s), never after the exact 1.5858 s
    assert t_share - 1e-9 <= onset <= EXACT_CONTACT
    assert EXACT_CONTACT - onset < 2 * H * math.sqrt(2) / (2 * math.sqrt(2) * V)   # within two cells of closing


def test_total_energy_is_conserved_with_musl_flip(disks):
    s = disks.series()
    drift = np.abs(s["total_energy"] - s["total_energy"][0]) / s["total_energy"][0]
    # after separation: conserved to a few percent
    assert drift[s["time"] > 3.0].max() < 0.02
    # during contact the hypoelastic (small-strain) energy measure is only accurate to O(strain),
    # and the impact strain is about 2 V / c = 0.17: the neo-Hookean case below shows the scheme itself conserves
    assert drift.max() < 2 * V / math.sqrt(1346.15 / RHO)


def test_total_energy_is_conserved_throughout_with_a_hyperelastic_material(tmp_path):
    scene = two_disks(end=2.6)
    scene["materials"]["rubber"]["model"] = "neo_hookean"
    s = run_scene(scene, tmp_path).series()
    drift = np.abs(s["total_energy"] - s["total_energy"][0]) / s["total_energy"][0]
    assert drift.max() < 0.02


def test_disks_rebound_and_momentum_stays_zero(disks):
    last = disks.frame(-1)
    f = last["fields"]
    lower_left = f["body"] == 0
    v_ll = (f["mass"][lower_left, None] * f["velocity"][lower_left]).sum(0) / f["mass"][lower_left].sum()
    assert np.all(v_ll < 0)                      # moving back towards the lower-left corner
    momentum = (f["mass"][:, None] * f["velocity"]).sum(0)
    assert np.abs(momentum).max() < 1e-12 * f["mass"].sum() * V
    s = disks.series()
    assert s["kinetic_energy"][-1] > 0.5 * s["kinetic_energy"][0]   # most of it recovered after separation
