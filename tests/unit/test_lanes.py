"""solver/lanes.py: the four-lane vector the 3D MLS kernels use (tests/unit/test_fused.py checks
the kernels themselves against the scalar ones)."""
import numpy as np
import pytest
from numba import njit
from numba.core.errors import TypingError

from solver import lanes

RNG = np.random.default_rng(18)
axpy, add_to_row = lanes.exact.axpy, lanes.exact.add_to_row   # (a kernel sees module globals, not attributes)
lanes_of, load_row, split = lanes.lanes_of, lanes.load_row, lanes.split


@njit
def _axpy_exact(a, x, y):
    return split(axpy(a, lanes_of(x[0], x[1], x[2], x[3]), lanes_of(y[0], y[1], y[2], y[3])))


@njit
def _add_rows_exact(rows, index, weights, values):
    for n in range(index.shape[0]):
        add_to_row(rows, np.uint64(index[n]), weights[n], load_row(values, np.uint64(n)))


def test_axpy_is_y_plus_a_times_x_rounded_as_numpy_rounds_it_lane_by_lane():
    for _ in range(100):
        a, x, y = RNG.normal(), RNG.normal(size=4), RNG.normal(size=4)
        assert np.array_equal(np.array(_axpy_exact(a, x, y)), y + a * x)


def test_rows_added_in_order_are_the_scalar_sums_to_the_bit():
    """add_to_row reads a row, adds a * x and writes it back, as rows[i, k] += a * x_k does."""
    index = RNG.integers(0, 7, size=200)
    weights, values = RNG.normal(size=200), RNG.normal(size=(200, 4))
    rows, expected = np.zeros((7, 4)), np.zeros((7, 4))
    _add_rows_exact(rows, index, weights, values)
    for n, i in enumerate(index):
        expected[i] += weights[n] * values[n]
    assert np.array_equal(rows, expected)


def test_the_row_intrinsics_refuse_an_array_that_is_not_c_contiguous():
    """A row is four doubles side by side: a strided view (numba's layout "A") is refused when the
    kernel compiles. (The width is not part of numba's type: the callers allocate (n, 4) rows.)"""
    _add_rows_exact(np.zeros((7, 4)), np.zeros(1, dtype=np.int64), np.ones(1), np.ones((1, 4)))   # compiles
    with pytest.raises(TypingError, match="add_to_row"):
        _add_rows_exact(np.zeros((7, 8))[:, ::2], np.zeros(1, dtype=np.int64), np.ones(1), np.ones((1, 4)))


@pytest.mark.parametrize("dimension", [2, 3])
def test_the_threads_rows_are_summed_into_mass_and_momentum_in_thread_order(dimension):
    """3D's rows are (m, mv_x, mv_y, mv_z), 2D's (m, mv_x, mv_y, 0): the fourth lane is not read in 2D."""
    rows = RNG.normal(size=(3, 50, 4))
    mass, momentum = np.empty(50), np.empty((50, dimension))
    lanes.unpack_mass_momentum(mass, momentum, rows)
    expected = (rows[0] + rows[1]) + rows[2]
    assert np.array_equal(mass, expected[:, 0]) and np.array_equal(momentum, expected[:, 1:1 + dimension])


def test_the_velocities_are_packed_with_a_zero_fourth_lane():
    v = RNG.normal(size=(20, 3))
    packed = np.full((20, 4), np.nan)
    lanes.pack_velocity(v, packed)
    assert np.array_equal(packed[:, :3], v) and np.all(packed[:, 3] == 0.0)
