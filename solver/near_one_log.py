"""log(x) for x near 1 in arithmetic LLVM can vectorise, the same bits as the C library's log.

A call to libm's log keeps a loop scalar: LLVM vectorises a loop only when every call in it has a
vector form, and numba's math.log is a call into the C library. The vectorised P2G
(solver/fused_template.py `_p2g_mls`) needs log J_p for the neo-Hookean stress, J_p near 1 in
most scenes, so it takes it from `log_near_one`, written out here as glibc (2.28 and later)
computes log on the interval it treats apart, [1 - 2^-4, 1 + 0x1.09p-4): r = x - 1, a degree-10
polynomial in r, and r^2 / 2 split in a high and a low part. The coefficients and the order of
the operations, every FMA included, are those of glibc's `__log_fma`, the variant it runs on a
CPU with FMA (read off its machine code on glibc 2.36). Outside the interval, the caller uses
math.log.

That is the same bits as libm only where libm is that code: another C library, or glibc on a CPU
without FMA (its SSE2 variant rounds differently), gives results an ulp apart in places. So
the kernels use it only where `matches_libm()` found it equal to math.log on a sample of the
interval and its ends, once per process; elsewhere they call math.log (correct, not vectorised).
"""
from __future__ import annotations

import functools
import math

import numpy as np
from llvmlite import ir
from solver.jit import njit
from numba.core import cgutils, types
from numba.extending import intrinsic

LOW = 0.9375                          # 1 - 2^-4: the interval's ends as glibc tests them
HIGH = float.fromhex("0x1.109p+0")    # 1 + 0x1.09p-4 (excluded)
_SPLIT = 134217728.0                  # 2^27: r's high part keeps 26 bits, so r_hi^2 is exact
# glibc's __log_data.poly1: B0 = -1/2, then the coefficients of r^3 ... r^12 over r^3
B0, B1, B2, B3, B4, B5, B6, B7, B8, B9, B10 = (float.fromhex(h) for h in (
    "-0x1p-1", "0x1.5555555555577p-2", "-0x1.ffffffffffdcbp-3", "0x1.999999995dd0cp-3", "-0x1.55555556745a7p-3",
    "0x1.24924a344de30p-3", "-0x1.fffffa4423d65p-4", "0x1.c7184282ad6cap-4", "-0x1.999eb43b068ffp-4",
    "0x1.78182f7afd085p-4", "-0x1.5521375d145cdp-4"))


@intrinsic
def fma(typingctx, a, b, c):
    """a * b + c rounded once (llvm.fma: an FMA instruction, in vectors too), whatever the
    kernel's fastmath flags."""
    def codegen(context, builder, signature, args):
        double = ir.DoubleType()
        function = cgutils.get_or_insert_function(builder.module, ir.FunctionType(double, [double] * 3),
                                                  "llvm.fma.f64")
        return builder.call(function, args)
    return types.float64(types.float64, types.float64, types.float64), codegen


# fastmath=False, said: a callee inherits its caller's flags otherwise (solver/fused.py `_quadratic`);
# contraction would fuse products glibc rounds. Not inline="always": LLVM inlines it, keeping its flags.
@njit(cache=True, fastmath=False)
def log_near_one(x):
    """log x for LOW <= x < HIGH, as glibc's log computes it there (any x: no trap, no branch)."""
    r = x - 1.0
    r2 = r * r
    r3 = r2 * r
    low_terms = fma(r2, B3, fma(r, B2, B1))
    middle_terms = fma(r2, B6, fma(r, B5, B4))
    high_terms = fma(r3, B10, fma(r2, B9, fma(r, B8, B7)))
    polynomial = fma(fma(high_terms, r3, middle_terms), r3, low_terms)
    r_hi = fma(-_SPLIT, r, fma(r, _SPLIT, r))
    r_hi2 = r_hi * r_hi
    hi = fma(r_hi2, B0, r)
    lo = fma(B0 * (r - r_hi), r + r_hi, fma(r_hi2, B0, r - hi))
    return hi + fma(polynomial, r3, lo)


@njit(cache=True)
def _differences(values):
    count = 0
    for x in values:
        count += log_near_one(x) != math.log(x)
    return count


def sample(count: int = 1 << 16) -> np.ndarray:
    """Points of [LOW, HIGH): spread over it, clustered at 1 (where J_p lies), and its ends."""
    rng = np.random.default_rng(2018)
    near = 1.0 + rng.normal(0.0, 1e-4, count // 2)
    edges = np.array([LOW, np.nextafter(HIGH, 0.0), 1.0, np.nextafter(1.0, 0.0), np.nextafter(1.0, 2.0)])
    values = np.concatenate([rng.uniform(LOW, HIGH, count // 2), near, edges])
    return values[(values >= LOW) & (values < HIGH)]


@functools.cache
def matches_libm() -> bool:
    """Whether `log_near_one` gives math.log's bits on `sample()` (this process's C library and CPU)."""
    return _differences(sample()) == 0
