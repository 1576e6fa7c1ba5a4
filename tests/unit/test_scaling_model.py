"""The weak-scaling model of benchmarks/scaling.py (docs/benchmarks.md, "Weak scaling to 1,024
processes"): its geometry, on measured inputs made up for the test."""
import math
import sys
from pathlib import Path

import pytest

# benchmarks/ on the path only while it imports (its service.py would hide the service package)
BENCHMARKS = str(Path(__file__).resolve().parents[2] / "benchmarks")
sys.path.insert(0, BENCHMARKS)
try:
    import scaling
finally:
    sys.path.remove(BENCHMARKS)

PARTICLES, FACE_NODES, BYTES_PER_NODE = 216_000, 31 ** 2, 80.0
ONE = {"wall_per_step": 0.03, "ranks": [{"particles": PARTICLES}]}
RANK = {"halo_bytes_per_step": BYTES_PER_NODE * FACE_NODES, "halo_seconds_per_step": 1e-3,
        "collective_seconds_per_step": 1e-3, "exchanges_per_step": 4, "collectives_per_step": 2}
MODEL = scaling.weak_model(ONE, {"wall_per_step": 0.016, "ranks": [RANK, RANK]}, FACE_NODES)


def test_two_slabs_of_the_bar_send_what_was_measured():
    two = scaling.projected(MODEL, 2, "slabs of a bar")
    assert two["halo"] == pytest.approx(BYTES_PER_NODE * FACE_NODES)
    assert two["messages"] == 4   # one neighbour, each exchange
    assert scaling.projected(MODEL, 64, "slabs of a bar")["halo"] == pytest.approx(2 * two["halo"])


def test_slabs_of_a_cube_cannot_be_cut_thinner_than_a_cell_layer():
    # 8 particles a cell: the cube of P processes is (P * 27,000) ** (1/3) cells a side
    side = {p: round((p * PARTICLES / 8) ** (1 / 3)) for p in (150, 200)}
    assert side[150] >= 150 and side[200] < 200
    assert scaling.projected(MODEL, 150, "slabs") is not None
    assert scaling.projected(MODEL, 200, "slabs") is None


def test_a_block_sends_the_same_halo_whatever_the_count_of_blocks_around_it():
    # 4 x 4 x 4 and 8 x 8 x 8: each block is 30 cells a side with two neighbours along each axis
    at_64, at_512 = (scaling.projected(MODEL, p, "blocks") for p in (64, 512))
    assert at_64["halo"] == pytest.approx(at_512["halo"]) == pytest.approx(6 * BYTES_PER_NODE * 30 ** 2)
    assert at_64["imbalance"] == at_512["imbalance"] == 1.0   # 120 and 240 cells cut evenly
    assert at_512["comm"] > at_64["comm"]                     # the collectives' log2(P)


@pytest.mark.parametrize("p,parts", [(1024, 3), (1024, 2), (512, 3), (12, 3)])
def test_the_process_grid_multiplies_to_the_process_count(p, parts):
    factors = scaling._cube_factors(p, parts)
    assert len(factors) == parts and math.prod(factors) == p
