"""`run(scene, out_dir)`: the time loop around the explicit step.

It owns what happens between steps: the time step size, the output frames,
the energy time series, the instability checks, progress reports and
cooperative stopping (a callback, SIGTERM or SIGINT). With several processes
every one runs this loop on its slab (sim.domain): decisions are collective,
rank 0 writes the result file and reports progress.
"""
from __future__ import annotations

import math
import signal
import threading
import time as wallclock
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable

from solver import __version__
from solver import checkpoint
from solver.fields import frame_fields
from solver.preview import finish_outputs
from solver.scene import Scene, load_scene
from solver.stepper import ExplicitMPM, Instability
from solver.tlmpm import TotalLagrangianMPM

# An energy above this many times what went in (initial energy plus the work of
# loads and boundary conditions) can only come from a numerical blow-up.
ENERGY_GROWTH_LIMIT = 2.0
# ... plus this fraction of sum(m c^2), so round-off around a zero-energy state is not flagged.
ENERGY_FLOOR = 1e-6
PROGRESS_INTERVAL_S = 0.25
MAX_SERIES_POINTS = 20_000
# Times closer than this fraction of a step count as equal (output times, the end time):
# one tolerance for both, so the last frame and the end are reached on the same step.
TIME_TOLERANCE = 1e-6
CHECK_EVERY = 20   # steps between finiteness and energy checks, at most


@dataclass
class ProgressInfo:
    step: int
    time: float
    end_time: float
    fraction: float
    steps_per_second: float | None
    eta_seconds: float | None
    dt: float
    energies: dict = field(default_factory=dict)


@dataclass
class Result:
    status: str              # "complete" | "partial"
    reason: str              # "finished" | "cancelled" | "unstable" | "max_steps"
    message: str
    steps: int
    time: float
    wall_seconds: float
    particles: int
    result_path: str
    out_dir: str

    def to_dict(self) -> dict:
        return asdict(self)


class _StopSignals:
    """SIGTERM / SIGINT set a flag (when run() is in the main thread) so the step in flight finishes."""

    def __init__(self):
        self.requested = False
        self._previous = {}

    def __enter__(self):
        if threading.current_thread() is threading.main_thread():
            for sig in (signal.SIGTERM, signal.SIGINT):
                self._previous[sig] = signal.signal(sig, self._handle)
        return self

    def _handle(self, signum, frame):
        self.requested = True

    def __exit__(self, *exc):
        for sig, handler in self._previous.items():
            signal.signal(sig, handler)


class _FrameSchedule:
    """`frames` output times evenly spaced over [0, end], first and last included."""

    def __init__(self, end: float, frames: int):
        self.times = [end * k / (frames - 1) for k in range(frames)]
        self.next = 0

    def due(self, t: float, dt: float) -> bool:
        return self.next < len(self.times) and t >= self.times[self.next] - TIME_TOLERANCE * dt

    def until_next(self, t: float) -> float:
        return self.times[self.next] - t if self.next < len(self.times) else math.inf


def run(
    scene: Scene | dict | str | Path,
    out_dir: str | Path,
    progress: Callable[[ProgressInfo], None] | None = None,
    should_stop: Callable[[], bool] | None = None,
    resume: bool = False,
    checkpoint_seconds: float | None = None,
) -> Result:
    """Run a scene to its end time; write result.h5, result.xdmf and preview.png into out_dir.

    Writes restart checkpoints (solver/checkpoint.py: the scene's `output.checkpoint`, else
    every `checkpoint_seconds`); `resume` continues from the one in out_dir when there is one.

    Never raises for a numerical instability: the run stops, the frames written
    so far stay readable with status "partial", and the Result names the step,
    particle and quantity.
    """
    scene = load_scene(scene)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    started = wallclock.perf_counter()

    stepper = TotalLagrangianMPM if scene.method.formulation == "tlmpm" else ExplicitMPM
    sim = stepper(scene)
    domain = sim.domain
    end = scene.time.end
    frames = _FrameSchedule(end, scene.output.frames)
    series_every = _series_stride(scene, sim)
    check_every = min(series_every, CHECK_EVERY)
    fixed_dt = scene.time.dt
    energy_floor = ENERGY_FLOOR * sim.energy_scale()
    initial_energy = sim.energies().total

    reason, message = "finished", ""
    last_report = started
    last_energies = {}
    dt = fixed_dt or sim.stable_time_step(scene.time.cfl)
    restart = checkpoint.resume(sim, out_dir) if resume else None
    if restart is not None:
        dt, frames.next = restart.dt, restart.frame_next

    writer = domain.writer(out_dir, scene, __version__)   # a ResultWriter on rank 0
    with writer, _StopSignals() as signals:
        checkpoints = checkpoint.Checkpointer(out_dir, scene, checkpoint.Policy.of(scene, checkpoint_seconds),
                                              writer, restart)
        try:
            while True:
                checkpoints.top_of_step(sim, dt, frames.next)
                if frames.due(sim.time, dt):
                    fields = domain.gather(frame_fields(sim, scene.output.fields))   # sorted by id
                    writer.write_frame(sim.step_count, sim.time, fields)
                    frames.next += 1
                finished = sim.time >= end - TIME_TOLERANCE * dt
                if finished or sim.step_count % check_every == 0:
                    sim.check_finite()
                    e = sim.energies()
                    last_energies = {"kinetic": e.kinetic, "strain": e.strain, "total": e.total}
                    if finished or sim.step_count % series_every == 0:
                        writer.append_series(time=sim.time, dt=dt, kinetic_energy=e.kinetic,
                                             strain_energy=e.strain, total_energy=e.total,
                                             external_work=e.external_work, boundary_work=e.boundary_work,
                                             **sim.reactions())
                    supplied = initial_energy + max(e.external_work, 0.0) + max(e.boundary_work, 0.0)
                    if not e.total <= ENERGY_GROWTH_LIMIT * supplied + energy_floor:
                        raise Instability(sim.step_count, sim.time, None, "total energy",
                                          f"{e.total:.6g} exceeds {ENERGY_GROWTH_LIMIT:g} x the energy supplied "
                                          f"({supplied:.6g}): the time step is probably too large")
                if finished:
                    break
                if sim.step_count >= scene.time.max_steps:
                    reason, message = "max_steps", f"stopped at time.max_steps = {scene.time.max_steps}"
                    break
                now = wallclock.perf_counter()
                asked = signals.requested   # a signal is honoured at the next step (a flag: no cost)
                if domain.root_says(now - last_report >= PROGRESS_INTERVAL_S):
                    last_report = now
                    if progress is not None and domain.is_root:
                        progress(_progress(sim, end, dt, started, now, last_energies))
                    asked = asked or (should_stop is not None and should_stop())
                if domain.any(asked):
                    reason, message = "cancelled", f"stopped on request at step {sim.step_count}"
                    break

                dt = fixed_dt or sim.stable_time_step(scene.time.cfl)
                # land exactly on output times and on the end time
                to_frame = frames.until_next(sim.time)
                dt = min(dt, to_frame) if to_frame > TIME_TOLERANCE * dt else dt
                sim.advance(dt)
        except Instability as err:
            reason, message = "unstable", str(err)
        checkpoints.finish(sim, reason)
        status = "complete" if reason == "finished" else "partial"
        writer.close(status)

    if domain.is_root:
        finish_outputs(out_dir, scene)
    wall = wallclock.perf_counter() - started
    if progress is not None and domain.is_root:
        progress(_progress(sim, end, dt, started, wallclock.perf_counter(), last_energies))
    return Result(status=status, reason=reason, message=message, steps=sim.step_count, time=sim.time,
                  wall_seconds=wall, particles=int(domain.sum(sim.particles.count)),
                  result_path=str(out_dir / "result.h5"), out_dir=str(out_dir))


def make_simulation(scene: Scene) -> ExplicitMPM:
    stepper = TotalLagrangianMPM if scene.method.formulation == "tlmpm" else ExplicitMPM
    return stepper(scene)


def _series_stride(scene, sim: ExplicitMPM) -> int:
    """Energies every N steps: the scene's N, or every step up to MAX_SERIES_POINTS points."""
    energies = scene.output.energies
    if energies is False:
        return 2**62
    if energies is not True:
        return int(energies)
    dt = scene.time.dt or sim.stable_time_step(scene.time.cfl)
    return max(1, math.ceil(scene.time.end / dt / MAX_SERIES_POINTS))


def _progress(sim: ExplicitMPM, end: float, dt: float, started: float, now: float, energies: dict) -> ProgressInfo:
    elapsed = now - started
    fraction = min(1.0, sim.time / end) if end > 0 else 1.0
    rate = sim.step_count / elapsed if elapsed > 0 and sim.step_count else None
    eta = None
    if fraction > 0 and elapsed > 0:
        eta = elapsed * (1.0 - fraction) / fraction
    return ProgressInfo(step=sim.step_count, time=sim.time, end_time=end, fraction=fraction,
                        steps_per_second=rate, eta_seconds=eta, dt=dt, energies=dict(energies))
