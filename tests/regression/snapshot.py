"""Run a scene for a fixed number of steps and fingerprint the state it reaches.

The regression cases (tests/regression/cases.py) are run on one commit and stored
(`python tests/regression/record.py`); tests/regression/test_regression.py runs them
again and compares. A fingerprint keeps, for every per-particle array and every
global quantity:

- the SHA-256 of its bytes: equal hashes mean the same bits;
- a sample of rows (particles evenly spaced in id order) and the column sums over
  all particles, so that where bits may legitimately differ (a changed order of
  summation) the test can still bound the difference relative to the values.

Storing whole arrays would take tens of MB for the 3D examples; the hash decides
bit identity, the sample and the sums bound round-off.

The cases run with MPM_FMA=0 (the default is 1: solver/fused_template.py CONTRACT):
without FMA contraction the fused kernels give the same bits on every CPU, so a
baseline recorded on one machine holds on another.
"""
from __future__ import annotations

import copy
import hashlib
import os
from pathlib import Path
from unittest import mock

import numpy as np

from solver.runner import make_simulation
from solver.scene_checks import load_scene

BASELINE = Path(__file__).with_name("baseline.npz")
SAMPLE_ROWS = 32
REPRODUCIBLE = {"MPM_FMA": "0"}


def run_case(case, reproducible: bool = True) -> dict[str, np.ndarray]:
    """The state after the case's steps, the time step chosen as the runner does (the
    fixed dt, else the stable step of the current state), with kernels whose bits do not
    depend on the CPU (REPRODUCIBLE), or with those of the environment (`reproducible`
    False: tests/regression/drift.py)."""
    if not reproducible:
        return _run(case)
    with mock.patch.dict(os.environ, REPRODUCIBLE):
        return _run(case)


def _run(case) -> dict[str, np.ndarray]:
    loaded = load_scene(copy.deepcopy(case.scene))
    sim = make_simulation(loaded)
    if case.general:
        sim.use_general_kernels()
    dts = []
    for _ in range(case.steps):
        dt = loaded.time.dt or sim.stable_time_step(loaded.time.cfl)
        sim.advance(dt)
        dts.append(dt)
    p = sim.particles
    order = np.argsort(p.id, kind="stable")
    state = {name: np.ascontiguousarray(a[order]) for name, a in p.arrays().items()}
    e = sim.energies()
    reactions = sim.reactions()
    state["global/energies"] = np.array([e.kinetic, e.strain, e.external_work, e.boundary_work])
    state["global/reactions"] = np.array([reactions[k] for k in sorted(reactions)], dtype=np.float64)
    state["global/dt"] = np.array(dts)
    state["global/time"] = np.array([sim.time])
    return state


def fingerprint(state: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """Flat name -> array entries for np.savez: hash, sample, column sums per array."""
    out = {}
    for name, a in sorted(state.items()):
        out[f"{name}|sha256"] = np.frombuffer(hashlib.sha256(np.ascontiguousarray(a).tobytes()).digest(), np.uint8)
        rows = a.reshape(a.shape[0], -1) if a.ndim > 0 and a.shape[0] else a.reshape(1, -1)
        pick = np.unique(np.linspace(0, rows.shape[0] - 1, min(SAMPLE_ROWS, rows.shape[0])).astype(np.int64))
        out[f"{name}|sample"] = rows[pick].astype(np.float64)
        out[f"{name}|sum"] = rows.astype(np.float64).sum(axis=0)
        out[f"{name}|abs_sum"] = np.abs(rows.astype(np.float64)).sum(axis=0)
    return out


def case_entries(baseline: dict[str, np.ndarray], name: str) -> dict[str, np.ndarray]:
    """One case's fingerprint out of the whole baseline (its keys are `case/array|part`)."""
    return {key[len(name) + 1:]: value for key, value in baseline.items() if key.startswith(f"{name}/")}


def differences(stored: dict[str, np.ndarray], fresh: dict[str, np.ndarray], relative: float | None) -> list[str]:
    """What differs between two fingerprints of one case. relative None: bits must be equal;
    else every sampled value and column sum within `relative` of the array's magnitude."""
    names = sorted({key.split("|")[0] for key in stored} | {key.split("|")[0] for key in fresh})
    problems = []
    for name in names:
        if f"{name}|sha256" not in stored or f"{name}|sha256" not in fresh:
            problems.append(f"{name}: present in only one of the two runs")
            continue
        if np.array_equal(stored[f"{name}|sha256"], fresh[f"{name}|sha256"]):
            continue
        if stored[f"{name}|sample"].shape != fresh[f"{name}|sample"].shape:
            problems.append(f"{name}: shape {fresh[f'{name}|sample'].shape}, stored {stored[f'{name}|sample'].shape}")
            continue
        if relative is None:
            problems.append(f"{name}: bits differ")
            continue
        moved = relative_difference(stored, fresh, name)
        if not moved <= relative:
            problems.append(f"{name}: differs by {moved:.3g} relative (allowed {relative:g})")
    return problems


def relative_difference(stored: dict[str, np.ndarray], fresh: dict[str, np.ndarray], name: str) -> float:
    """How far one array of two fingerprints apart: the larger of its column sums' and its
    sampled rows' largest difference, each relative to the stored array's magnitude."""
    scale = max(float(np.max(stored[f"{name}|abs_sum"], initial=0.0)), 1e-300)
    row_scale = max(float(np.max(np.abs(stored[f"{name}|sample"]), initial=0.0)), 1e-300)
    sums = np.max(np.abs(stored[f"{name}|sum"] - fresh[f"{name}|sum"]), initial=0.0) / scale
    sample = np.max(np.abs(stored[f"{name}|sample"] - fresh[f"{name}|sample"]), initial=0.0) / row_scale
    return float(max(sums, sample))
