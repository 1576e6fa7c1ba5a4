"""Every example and a matrix of methods give the stored results (tests/regression/baseline.npz).

The baseline was recorded on the commit before the step architecture was rewritten
(`python tests/regression/record.py`); a refactor must give the same bits at the same
thread count. Bits depend on the compiler too: the cases run with the fused kernels compiled
without FMA contraction (MPM_FMA=0, tests/regression/snapshot.py), whose bits do not depend
on the CPU, and with the numba of scripts/constraints.txt. Where a change legitimately reorders a sum, or the CPU sets the last bit, the case says so in
ROUND_OFF with the reason, and is held to 1e-12 of the values instead. A change that reorders the sums
of many cases re-records them (`record.py CASE ...`) and says in its commit message how far each moved
(tests/regression/drift.py measures it): the fused kernels' row sums did so for 106 cases (f94fc5d).
The default run leaves out most of the 3D method matrix, each case a 3D kernel variant to compile
(cases.py `_slow_3d`); `-m slow` runs them.
"""
from __future__ import annotations

import json
import re

import numpy as np
import pytest

from cases import cases, duplicates
from snapshot import BASELINE, case_entries, differences, fingerprint, run_case

CASES = cases()
DUPLICATES = duplicates()
# numpy evaluates a scene expression's sin, cos, exp, ... on arrays with SIMD code picked for
# the CPU (AVX-512 or not), whose last bit differs between machines: a scene driven by such an
# expression reproduces the baseline of another machine to round-off, not bit for bit
TRANSCENDENTAL = re.compile(r"\b(sin|cos|tan|asin|acos|atan|sinh|cosh|tanh|exp|log)\(")
# case name -> why it is held to 1e-12 of the values instead of the bits
ROUND_OFF: dict[str, str] = {
    name: "numpy's transcendental functions differ in the last bit between CPUs"
    for name, case in CASES.items() if TRANSCENDENTAL.search(json.dumps(case.scene))}


@pytest.fixture(scope="module")
def baseline():
    with np.load(BASELINE) as stored:
        return {key: stored[key] for key in stored.files}


def test_every_case_has_a_baseline(baseline):
    recorded = {key.split("/", 1)[0] for key in baseline}
    assert recorded == set(CASES) | set(DUPLICATES)


@pytest.mark.parametrize("name", sorted(DUPLICATES))
def test_a_duplicate_case_has_the_stored_result_of_the_case_it_repeats(baseline, name):
    assert not differences(case_entries(baseline, DUPLICATES[name]), case_entries(baseline, name), None)


@pytest.mark.parametrize("name", [pytest.param(name, marks=pytest.mark.slow) if case.slow else name
                                  for name, case in CASES.items()])
def test_case_gives_the_stored_result(baseline, name):
    stored = case_entries(baseline, name)
    fresh = fingerprint(run_case(CASES[name]))
    problems = differences(stored, fresh, 1e-12 if name in ROUND_OFF else None)
    assert not problems, "\n".join(problems)
