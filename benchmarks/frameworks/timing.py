"""The timing every framework script shares: compile, then the best of three timed runs."""
import json
import time


def report_rate(step, sync, n_particles: int, steps: int, positions) -> None:
    """Print one JSON line: the best particle-steps/s of three runs of `steps` steps (after
    three untimed ones that compile), and the mean position (a check that the step ran)."""
    for _ in range(3):          # compile
        step()
    sync()
    best = 0.0
    for _ in range(3):
        start = time.perf_counter()
        for _ in range(steps):
            step()
        sync()
        best = max(best, n_particles * steps / (time.perf_counter() - start))
    print(json.dumps({"rate": best, "x_mean": float(positions().mean())}))
