"""Record the regression baseline: `python tests/regression/record.py [CASE ...]`.

Runs every case of tests/regression/cases.py and writes tests/regression/baseline.npz.
Run it on the commit whose results are the reference; the test compares later commits
against it. With case names, only those are re-recorded (the others are kept).
"""
from __future__ import annotations

import sys
import time

import numpy as np

from cases import cases, duplicates
from snapshot import BASELINE, fingerprint, run_case


def main(names: list[str]) -> None:
    stored = dict(np.load(BASELINE)) if BASELINE.exists() and names else {}
    for name, case in cases().items():
        if names and name not in names:
            continue
        started = time.perf_counter()
        for key, value in fingerprint(run_case(case)).items():
            stored[f"{name}/{key}"] = value
        print(f"{name}: {time.perf_counter() - started:.1f} s", flush=True)
    for duplicate, case in duplicates().items():   # a case run scene for scene by another: its entries
        for key in [key for key in stored if key.startswith(f"{case}/")]:
            stored[duplicate + key[len(case):]] = stored[key]
    np.savez_compressed(BASELINE, **stored)
    print(f"wrote {BASELINE} ({BASELINE.stat().st_size / 1e6:.1f} MB)")


if __name__ == "__main__":
    main(sys.argv[1:])
