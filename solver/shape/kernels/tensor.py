"""The tensor product shared by every shape function.

A shape function module gives its 1D function as a numba function

    axis(s, a, p, cells, inv_h, data, w1, g1) -> first node, or -1 outside the grid

of the position s along axis a in cells from the grid's lower end (cells: the
axis's cell count, inv_h: 1/h, data: the function's per-particle data, e.g.
GIMP's box sides, or an empty array). It fills w1[a, j] and g1[a, j] (the derivative,
already divided by h) for the `support` nodes first + j, and must test s itself
(catching NaN). The kernel made from weights_template.py for each module (`kernels`)
does the rest: the particle loop on the threads' blocks and the tensor products (`scatter`). The stencil node k has the
per-axis offsets j_a = (k // support**a) % support (axis 0 fastest, like the
node order).
"""
from __future__ import annotations

import functools
from importlib import import_module
from pathlib import Path

import numpy as np
from solver.jit import njit

from solver import generated

NO_DATA = np.zeros((0, 0))   # `data` of the functions that need none
_SUPPORTS = {n: np.empty((0,) * n) for n in range(1, 6)}


def nodes_of(module: str) -> np.ndarray:
    """The support declared in solver/shape/<module>.py (its first name) as `weights` takes it:
    an empty array of that rank, a compile-time constant of the kernel."""
    support = import_module(f"solver.shape.{module}").SHAPE_FUNCTIONS[0].support
    return _SUPPORTS[support]


_IMPORT_LINE = "from solver.shape.kernels.quadratic_bspline import axis"
_TEMPLATE = Path(__file__).with_name("weights_template.py")


@functools.cache
def kernels(module: str):
    """The weights kernel of solver/shape/kernels/<module>.py, generated from
    weights_template.py with that module's `axis` (see there why): `kernels(m).weights(
    nodes, spec, x, data, lower, inv_h, cells, strides, idx, w, dw, blocks)`."""
    text = _TEMPLATE.read_text()
    if _IMPORT_LINE not in text:
        raise RuntimeError(f"{_TEMPLATE} lost its import line {_IMPORT_LINE!r}")
    text = text.replace(_IMPORT_LINE, f"from solver.shape.kernels.{module} import axis")
    return generated.load("shape", f"weights_{module}", text)


@njit(cache=True)
def scatter(p, nodes, dims, base, w1, g1, strides, idx, w, dw):
    """Fill idx[p], w[p], dw[p] with the tensor products of the 1D weights (the support
    nodes.ndim and the dimension len(dims) compile-time constants: the divisions below
    become multiplications)."""
    dim, support = len(dims), nodes.ndim
    nk = support**dim
    for k in range(nk):
        node = 0
        wk = 1.0
        rest = k
        for a in range(dim):
            j = rest % support
            rest //= support
            node += (base[a] + j) * strides[a]
            wk *= w1[a, j]
        idx[p, k] = node
        w[p, k] = wk
        for d in range(dim):
            g = 1.0
            rest = k
            for a in range(dim):
                j = rest % support
                rest //= support
                g *= g1[a, j] if a == d else w1[a, j]
            dw[p, k, d] = g
