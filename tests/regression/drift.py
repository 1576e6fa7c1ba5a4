"""How far the default kernels move the regression cases from the baseline:
`python tests/regression/drift.py [CASE ...]`.

The baseline (tests/regression/baseline.npz) and the tests run with MPM_FMA=0, whose bits
do not depend on the CPU. Runs use FMA contraction unless told otherwise, which changes the
last bits of the fused kernels' sums; this script runs the cases with the environment's
setting and prints, per case, the array that moved furthest from the stored fingerprint
(relative to that array's magnitude, as the ROUND_OFF tolerance of test_regression.py reads
it), the furthest first. Nothing is asserted: it is a measurement.
"""
from __future__ import annotations

import sys
import time

import numpy as np

from cases import cases
from snapshot import BASELINE, case_entries, fingerprint, relative_difference, run_case

# An array whose stored values are all below this (SI units) holds round-off only (the stress
# of bodies in free flight, about 1e-14 Pa): its difference relative to itself says nothing.
ROUND_OFF_MAGNITUDE = 1e-9


def furthest(stored: dict[str, np.ndarray], fresh: dict[str, np.ndarray]) -> tuple[float, str, int]:
    """(difference, array, how many arrays changed bits) of one case; arrays of round-off
    magnitude are counted as changed but not measured."""
    names = sorted({key.split("|")[0] for key in fresh})
    changed = [n for n in names if not np.array_equal(stored[f"{n}|sha256"], fresh[f"{n}|sha256"])]
    moved = [(relative_difference(stored, fresh, n), n) for n in changed
             if np.max(np.abs(stored[f"{n}|sample"]), initial=0.0) >= ROUND_OFF_MAGNITUDE]
    worst = max(moved, default=(0.0, "-"))
    return worst[0], worst[1], len(changed)


def main(names: list[str]) -> None:
    with np.load(BASELINE) as baseline:
        stored_all = {key: baseline[key] for key in baseline.files}
    rows = []
    for name, case in cases().items():
        if names and name not in names:
            continue
        started = time.perf_counter()
        moved, array, changed = furthest(case_entries(stored_all, name), fingerprint(run_case(case, reproducible=False)))
        rows.append((moved, name, array, changed))
        print(f"{name}: {moved:.2e} ({array}; {changed} arrays changed) {time.perf_counter() - started:.1f} s",
              flush=True)
    rows.sort(reverse=True)
    print("\nfurthest first: relative difference, case, array, arrays whose bits changed")
    for moved, name, array, changed in rows:
        print(f"{moved:10.2e}  {name}  {array}  {changed}")
    same = sum(1 for row in rows if row[3] == 0)
    print(f"\n{same} of {len(rows)} cases the same bits as the baseline")


if __name__ == "__main__":
    main(sys.argv[1:])
