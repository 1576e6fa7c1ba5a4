"""Steppers timed side by side: alternate rounds, so a shared machine's load hits them alike."""
from __future__ import annotations

import time


def round_times(sims: dict, rounds: int, steps: int) -> dict[object, list[float]]:
    """For each key of `sims` ({key: (ExplicitMPM, dt)}), the seconds per particle-step of
    each of `rounds` rounds of `steps` steps, the steppers taking turns within a round."""
    times = {key: [] for key in sims}
    for _ in range(rounds):
        for key, (sim, dt) in sims.items():
            start = time.perf_counter()
            for _ in range(steps):
                sim.advance(dt)
            times[key].append((time.perf_counter() - start) / (steps * sim.particles.count))
    return times
