"""Four float64 lanes in one value, for the 3D MLS kernels (solver/fused_template.py `_p2g_lanes`,
`_g2p_lanes`) and 2D's MLS scatter (`p2g_mls_lanes`): a node's (m, mv_x, mv_y, mv_z), (m, mv_x,
mv_y, 0) or (v_x, v_y, v_z, 0) as one LLVM <4 x double>.

A 3D P2G adds four values into every one of a particle's 27 nodes, and a 3D G2P gathers three
from each. Written with scalars, that is 4 loads, 4 adds and 4 stores a node (3 loads and 6
FMAs in G2P); numba's LLVM vectorises neither (its loop vectorizer does not reach these loops,
its SLP vectorizer is off: docs/benchmarks.md, issue 18, seventeenth and twentieth parts). With
the node's values side by side in a row of an (n, 4) array, they are one vector load, one
vector FMA and one vector store. numba has no vector type, so this module gives it one,
`float64x4`, and the few operations the kernels need, as intrinsics (LLVM IR, inlined).

Each lane does the operations the scalar kernels do on its component, in their order: x * a + y
is the same product and sum, so the results are the same bits, with the kernels' contraction
(`contracted`: LLVM may fuse the product and the sum, as it does in the scalar kernels) and
without (`exact`, for MPM_FMA=0).
"""
from __future__ import annotations

from types import SimpleNamespace

from llvmlite import ir
from numba import types
from numba.extending import intrinsic, models, register_model

from solver.jit import njit, prange

_DOUBLE = ir.DoubleType()
_VECTOR = ir.VectorType(_DOUBLE, 4)
_INDEX = ir.IntType(32)


class Float64x4(types.Type):
    """Four float64 lanes in one value (LLVM <4 x double>): lives in registers only."""
    def __init__(self):
        super().__init__(name="float64x4")


float64x4 = Float64x4()


@register_model(Float64x4)
class _Float64x4Model(models.PrimitiveModel):
    def __init__(self, dmm, fe_type):
        super().__init__(dmm, fe_type, _VECTOR)


def _vector(builder, values):
    vector = ir.Constant(_VECTOR, ir.Undefined)
    for lane, value in enumerate(values):
        vector = builder.insert_element(vector, value, ir.Constant(_INDEX, lane))
    return vector


def _rows_of_four(array) -> bool:
    """Whether a kernel's argument is what the row intrinsics assume: a C-contiguous 2D float64 array
    (of rows of 4: the width is not part of numba's type, so the callers allocate (n, 4) rows)."""
    return isinstance(array, types.Array) and array.ndim == 2 and array.layout == "C" and array.dtype == types.float64


def _row(context, builder, array_type, array, row):
    """A pointer to row `row` of a C-contiguous (n, 4) float64 array, as one vector."""
    data = context.make_array(array_type)(context, builder, array).data
    start = builder.gep(data, [builder.mul(row, ir.Constant(row.type, 4))])
    return builder.bitcast(start, _VECTOR.as_pointer())


@intrinsic
def lanes_of(typingctx, a, b, c, d):
    """(a, b, c, d) as one float64x4."""
    def codegen(context, builder, signature, args):
        return _vector(builder, args)
    return float64x4(types.float64, types.float64, types.float64, types.float64), codegen


@intrinsic
def split(typingctx, lanes):
    """The four lanes as a tuple of floats."""
    def codegen(context, builder, signature, args):
        values = [builder.extract_element(args[0], ir.Constant(_INDEX, lane)) for lane in range(4)]
        return context.make_tuple(builder, signature.return_type, values)
    return types.UniTuple(types.float64, 4)(float64x4), codegen


@intrinsic
def load_row(typingctx, array, row):
    """array[row, 0:4] of a C-contiguous (n, 4) float64 array as one float64x4 (no bounds check,
    as numba's own indexing)."""
    if not _rows_of_four(array):
        return None

    def codegen(context, builder, signature, args):
        return builder.load(_row(context, builder, signature.args[0], *args), align=8)
    return float64x4(array, row), codegen


def _operations(flags: tuple) -> SimpleNamespace:
    """`axpy` and `add_to_row`, their products and sums carrying `flags` (contraction, or none)."""
    def multiply_add(builder, a, x, y):
        return builder.fadd(y, builder.fmul(_vector(builder, [a] * 4), x, flags=flags), flags=flags)

    @intrinsic
    def axpy(typingctx, a, x, y):
        """y + a * x, a a float (every lane's: y_k + a x_k)."""
        def codegen(context, builder, signature, args):
            return multiply_add(builder, *args)
        return float64x4(types.float64, float64x4, float64x4), codegen

    @intrinsic
    def add_to_row(typingctx, array, row, a, x):
        """array[row, 0:4] += a * x, in one load and one store (the scatter of a node)."""
        if not _rows_of_four(array):
            return None

        def codegen(context, builder, signature, args):
            pointer = _row(context, builder, signature.args[0], args[0], args[1])
            builder.store(multiply_add(builder, args[2], args[3], builder.load(pointer, align=8)), pointer, align=8)
            return context.get_dummy_value()
        return types.none(array, row, types.float64, float64x4), codegen

    return SimpleNamespace(axpy=axpy, add_to_row=add_to_row)


contracted = _operations(("contract",))
exact = _operations(())


@njit(parallel=True, cache=True)
def pack_velocity(v_new, v_lanes):
    """v_lanes[i] = (v_x, v_y, v_z, 0) of node i: G2P's velocities, one vector a node."""
    for i in prange(v_new.shape[0]):
        v_lanes[i, 0], v_lanes[i, 1], v_lanes[i, 2], v_lanes[i, 3] = v_new[i, 0], v_new[i, 1], v_new[i, 2], 0.0


@njit(parallel=True, cache=True)
def unpack_mass_momentum(grid_mass, grid_mom, lanes):
    """grid_mass, grid_mom from the threads' (m, mv_x, mv_y, mv_z) rows (2D: (m, mv_x, mv_y, 0)),
    summed in thread order: the sums solver/fused.py `_reduce_mass_momentum` forms from a grid and
    its copies."""
    threads, dim = lanes.shape[0], grid_mom.shape[1]
    for i in prange(grid_mass.shape[0]):
        m, px, py, pz = lanes[0, i, 0], lanes[0, i, 1], lanes[0, i, 2], lanes[0, i, 3]
        for t in range(1, threads):
            m += lanes[t, i, 0]
            px += lanes[t, i, 1]
            py += lanes[t, i, 2]
            pz += lanes[t, i, 3]
        grid_mass[i], grid_mom[i, 0], grid_mom[i, 1] = m, px, py
        if dim == 3:
            grid_mom[i, 2] = pz

