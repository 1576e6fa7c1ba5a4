"""log_near_one (solver/near_one_log.py): glibc's log near 1 in arithmetic LLVM vectorises."""
from __future__ import annotations

import math
import platform

import numpy as np
from numba import njit

from solver import near_one_log


@njit(cache=True)
def _logs(values):
    out = np.empty_like(values)
    for k in range(values.size):
        out[k] = near_one_log.log_near_one(values[k])
    return out


def _ulps(values: np.ndarray) -> np.ndarray:
    """How many units in the last place log_near_one is from the C library's log (Python's math.log)."""
    exact = np.array([math.log(x) for x in values])
    return np.abs(_logs(values) - exact) / np.spacing(np.abs(exact))


def test_it_is_within_an_ulp_of_the_c_librarys_log_on_its_interval():
    """Whatever the C library: glibc's bound on this code is 0.52 ulp from the exact log, the library's
    own log is within about as much, so the two are never an ulp apart."""
    values = near_one_log.sample()
    assert values.min() == near_one_log.LOW and values.max() == np.nextafter(near_one_log.HIGH, 0.0)
    assert _ulps(values[values != 1.0]).max() <= 1.0
    assert _logs(np.array([1.0]))[0] == 0.0 and not np.signbit(_logs(np.array([1.0]))[0])


def test_it_is_glibcs_log_to_the_bit_on_glibc_with_fma():
    """On glibc with an FMA unit (`__log_fma`, the code transcribed) every sample is the same bits,
    and `matches_libm` says so; elsewhere it says whether they are, and the kernels call math.log
    where they are not (tests/unit/test_fused.py)."""
    glibc = platform.libc_ver()[0] == "glibc"
    fma = "fma" in open("/proc/cpuinfo").read().split() if platform.system() == "Linux" else False
    same = bool(np.all(_ulps(near_one_log.sample()) == 0.0))
    assert near_one_log.matches_libm() == same
    if glibc and fma and platform.machine() == "x86_64":
        assert same


def test_outside_its_interval_it_is_not_the_log():
    """Its polynomial is glibc's for |x - 1| < 1/16 only: further out the caller must call math.log
    (the P2G counts those particles), which this shows is needed, not a formality."""
    assert np.all(_ulps(np.array([0.5, 0.8, 1.25, 2.0])) > 1000.0)
