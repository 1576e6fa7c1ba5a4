"""Displacement error norms of manufactured solutions ([R] Appendix A.2-A.3,
VERIFICATION_CASES D.1-D.2), shared by the verification tests and benchmarks.

At a time t^n, with u_p^h = x_p - X_p the computed displacement:

    e(t^n) = sqrt( sum_p V_p ||u_p^h - u(X_p, t^n)||^2 / V_tot )      (A.11)
    e1 = max_n e(t^n)                                                  (A.12)
    e2 = sqrt( sum_n sum_p V_p ||u_p^h - u||^2 / sum_n sum_p V_p ||u||^2 )   (A.13)

V_p is the reference volume V_p^0 (the TLMPM form of [R]; for ULMPM we use it
too, so both formulations are measured with the same weights) and V_tot its sum.
The sums over n run over the sampled times: the output frames of a run, which
are spaced evenly over the period (the source sums over every step; the frames
sample the same integral in time).
"""
from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np


class DisplacementErrors:
    """Accumulates e(t^n) and the sums of e2 over sampled times."""

    def __init__(self):
        self.times: list[float] = []
        self.local: list[float] = []     # e(t^n)
        self._error_sum = 0.0
        self._exact_sum = 0.0

    def add(self, t: float, X: np.ndarray, x: np.ndarray, volume0: np.ndarray, u_exact: np.ndarray) -> None:
        du = (x - X) - u_exact
        error = float(np.sum(volume0 * np.sum(du * du, axis=1)))
        self.times.append(t)
        self.local.append(float(np.sqrt(error / np.sum(volume0))))
        self._error_sum += error
        self._exact_sum += float(np.sum(volume0 * np.sum(u_exact * u_exact, axis=1)))

    @property
    def e1(self) -> float:
        return max(self.local)

    @property
    def e2(self) -> float:
        return float(np.sqrt(self._error_sum / self._exact_sum))


def errors_of_result(path, displacement: Callable[[np.ndarray, float], np.ndarray]) -> DisplacementErrors:
    """The norms of a result file against u = displacement(X, t).

    X is the position of each particle (by id) in the first frame; V_p^0 is taken
    proportional to the particle mass, exact for a body of one density.
    """
    from solver.results import list_frames, read_frame

    errors = DisplacementErrors()
    X = None
    for info in list_frames(path):
        frame = read_frame(path, info["index"])
        f = frame["fields"]
        order = np.argsort(f["id"])
        x, mass = f["position"][order], f["mass"][order]
        if X is None:
            X = x.copy()
        errors.add(frame["time"], X, x, mass, displacement(X, frame["time"]))
    return errors


def observed_orders(h: Sequence[float], e: Sequence[float]) -> list[float]:
    """Local orders log(e_k / e_k+1) / log(h_k / h_k+1) between successive refinements."""
    return [float(np.log(e[k] / e[k + 1]) / np.log(h[k] / h[k + 1])) for k in range(len(h) - 1)]


def fitted_order(h: Sequence[float], e: Sequence[float]) -> float:
    """Least-squares slope of log e against log h ([R] A.15)."""
    return float(np.polyfit(np.log(h), np.log(e), 1)[0])
