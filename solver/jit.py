"""numba's `njit` and `prange` for the solver's kernels, with the solver's kernel cache
installed first (solver/kernel_cache.py says why): every module that defines a kernel
imports them from here, so no kernel's cache is set up before the cache is."""
from numba import njit, prange

from solver import kernel_cache

kernel_cache.install()

__all__ = ["njit", "prange"]
