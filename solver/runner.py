"""`run(scene, out_dir)`: the time loop around the explicit step.

It owns what happens between steps: the time step size, the output frames,
the energy time series, the instability checks, progress reports and
cooperative stopping (a callback, SIGTERM or SIGINT). With several processes
every one runs this loop on its slab (sim.domain): decisions are collective,
rank 0 writes the result file and reports progress.
"""
from __future__ import annotations

import gc
import math
import signal
import threading
import time as wallclock
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable

from solver import checkpoint, cost, energy, precompile, series
from solver.compile_meter import CompileMeter
from solver.fields import frame_fields
from solver.progress import RateMeter
from solver.scene import Scene
from solver.scene_checks import load_scene
from solver.stepper import ExplicitMPM, Instability
from solver.version import __version__

# An energy above this many times what went in (initial energy plus the work of
# loads and boundary conditions) can only come from a numerical blow-up.
ENERGY_GROWTH_LIMIT = 2.0
# ... plus this fraction of sum(m c^2), so round-off around a zero-energy state is not flagged.
ENERGY_FLOOR = 1e-6
PROGRESS_INTERVAL_S = 0.25
MAX_SERIES_POINTS = series.MAX_SERIES_POINTS
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
    stage: str = "stepping"   # "compiling" (kernels before the first step) | "stepping" | "writing"


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
    compiled: int = 0              # kernels numba compiled in this run (0: all came from the cache)
    compile_seconds: float = 0.0   # wall time spent compiling them

    def to_dict(self) -> dict:
        return asdict(self)


class _StopSignals:
    """SIGTERM / SIGINT set a flag (when run() is in the main thread) so the step in flight finishes.

    The handlers stay until run() returns, not only while it steps: once the ranks have
    stopped together on one rank's signal, another rank's own signal may come later (Slurm
    signals a preempted job's processes node by node, and more than once), while rank 0 still
    writes the checkpoint and the previews; with the default handler back it would kill that
    rank, and MPI's launcher the others with it, before anything was written. run()'s caller
    gets its handlers back (a notebook's Ctrl-C works again); the command line ignores stops
    from there to its exit (solver/cli.py)."""

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
    """`frames` output times evenly spaced over [0, end], first and last included; each
    computed when it is next (no list: the memory does not grow with the frame count)."""

    def __init__(self, end: float, frames: int):
        self.end, self.count = end, frames
        self.next = 0

    def time(self, k: int) -> float:
        return self.end * k / (self.count - 1)

    def due(self, t: float, dt: float) -> bool:
        return self.next < self.count and t >= self.time(self.next) - TIME_TOLERANCE * dt

    def until_next(self, t: float) -> float:
        return self.time(self.next) - t if self.next < self.count else math.inf


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
    with _Compiling(scene, started, progress) as compiling:
        result = _run(scene, out_dir, started, compiling, progress, should_stop, resume, checkpoint_seconds)
    if compiling.threads and (compiling.meter.count or not cost.is_compiled(scene, compiling.threads)):
        cost.mark_compiled(scene, compiling.threads, compiling.meter.seconds, compiling.meter.count)
    result.compiled, result.compile_seconds = compiling.meter.count, round(compiling.meter.seconds, 3)
    return result


def _run(scene, out_dir, started, compiling, progress, should_stop, resume, checkpoint_seconds) -> Result:
    sim = make_simulation(scene)
    compiling.start_helper(sim.threads)   # (before the loop's set-up, which compiles kernels too)
    loop = _TimeLoop(scene, sim, started, progress, should_stop)
    del sim   # the loop holds it alone, so that `release` lets its arrays go before the previews
    loop.compiling = compiling
    restart = checkpoint.resume(loop.sim, out_dir) if resume else None
    if restart is not None:
        loop.dt, loop.frames.next = restart.dt, restart.frame_next
        if len(restart.series.get("total_energy", ())):   # the balance is against t = 0
            loop.initial_energy = float(restart.series["total_energy"][0])
    domain = loop.sim.domain
    writer = domain.writer(out_dir, scene, __version__)   # a ResultWriter on rank 0
    with _StopSignals() as signals:
        with writer:
            checkpoints = checkpoint.Checkpointer(out_dir, scene, checkpoint.Policy.of(scene, checkpoint_seconds),
                                                  writer, restart)
            reason, message = loop.run(writer, checkpoints, signals)
            loop.report(wallclock.perf_counter(), stage="writing")
            checkpoints.finish(loop.sim, reason)
            status = "complete" if reason == "finished" else "partial"
            writer.close(status)
        particles = int(domain.sum(loop.sim.particles.count))
        loop.release()   # the preview reads the last frame back: not beside the particles' and grid's arrays
        if domain.is_root:
            from solver.preview import finish_outputs   # matplotlib: a second of imports, not before the first step
            finish_outputs(out_dir, scene)
    wall = wallclock.perf_counter() - started
    loop.report(wallclock.perf_counter(), stage="writing")
    return Result(status=status, reason=reason, message=message, steps=loop.sim.step_count, time=loop.sim.time,
                  wall_seconds=wall, particles=particles, result_path=str(out_dir / "result.h5"), out_dir=str(out_dir))


@dataclass
class _Ended:
    """What is left of a simulation once its run has ended: what the last report reads."""
    step_count: int
    time: float
    domain: object


class _TimeLoop:
    """The steps of one run between its start and its end, a stop or an instability."""

    def __init__(self, scene: Scene, sim: ExplicitMPM, started: float, progress, should_stop):
        self.started = started
        self.scene, self.sim = scene, sim
        self.progress, self.should_stop = progress, should_stop
        self.end = scene.time.end
        self.frames = _FrameSchedule(self.end, scene.output.frames)
        self.series_every = _series_stride(scene, sim)
        self.check_every = min(self.series_every, CHECK_EVERY)
        self.next_finite_check = 0
        self.energy_floor = ENERGY_FLOOR * sim.energy_scale()
        self.initial_energy = sim.energies().total
        self.last_report = self.started
        self.rates = RateMeter()
        self.last_energies = {}
        self.dt = scene.time.dt or sim.stable_time_step(scene.time.cfl)
        self.compiling: _Compiling | None = None

    def run(self, writer, checkpoints, signals) -> tuple[str, str]:
        """(reason, message) of the end: finished, max_steps, cancelled or unstable."""
        sim, scene = self.sim, self.scene
        try:
            while True:
                checkpoints.top_of_step(sim, self.dt, self.frames.next)
                if self.frames.due(sim.time, self.dt):
                    fields = sim.domain.gather(frame_fields(sim, scene.output.fields))   # sorted by id
                    writer.write_frame(sim.step_count, sim.time, fields)
                    self.frames.next += 1
                finished = sim.time >= self.end - TIME_TOLERANCE * self.dt
                if finished or sim.step_count % self.check_every == 0:
                    self._check(writer, finished)
                if finished:
                    return "finished", ""
                if sim.step_count >= scene.time.max_steps:
                    return "max_steps", f"stopped at time.max_steps = {scene.time.max_steps}"
                if self._stop_requested(signals):
                    return "cancelled", f"stopped on request at step {sim.step_count}"
                self._advance()
                if self.compiling is not None and self.compiling.active:
                    self.compiling.done()
                    self.report(wallclock.perf_counter())   # the first step: the rates' origin
        except Instability as err:
            return "unstable", str(err)

    def _check(self, writer, finished: bool) -> None:
        """Finite state and bounded energy; the energy series row when due.

        The particles' finiteness is read every CHECK_EVERY steps (a pass over x, v and the
        stress: 2 % of the Taylor bar's step when the series asks for the energies every step),
        and at once when the energy is not finite, so that the error names the particle."""
        sim = self.sim
        e = sim.energies()
        if finished or sim.step_count >= self.next_finite_check or not math.isfinite(e.total):
            sim.check_finite()
            self.next_finite_check = sim.step_count + CHECK_EVERY
        self.last_energies = {"kinetic": e.kinetic, "strain": e.strain, "total": e.total,
                              "balance": e.balance, "error": e.balance - self.initial_energy}
        if finished or sim.step_count % self.series_every == 0:
            writer.append_series(time=sim.time, dt=self.dt, **energy.series_row(e, self.initial_energy),
                                 **sim.reactions(), **series.row(sim), **sim.thermal_series())
        supplied = self.initial_energy + e.supplied_work + sim.expansion_energy_bound()
        if not e.total <= ENERGY_GROWTH_LIMIT * supplied + self.energy_floor:
            raise Instability(sim.step_count, sim.time, None, "total energy",
                              f"{e.total:.6g} exceeds {ENERGY_GROWTH_LIMIT:g} x the energy supplied "
                              f"({supplied:.6g}): the time step is probably too large")

    def _stop_requested(self, signals) -> bool:
        """A signal, or the caller's should_stop at a progress report; decided together by all processes."""
        domain = self.sim.domain
        now = wallclock.perf_counter()
        asked = signals.requested   # a signal is honoured at the next step (a flag: no cost)
        if domain.root_says(now - self.last_report >= PROGRESS_INTERVAL_S):
            self.last_report = now
            if self.compiling is None or not self.compiling.active:   # else its thread reports
                self.report(now)
            asked = asked or (self.should_stop is not None and self.should_stop())
        return domain.any(asked)

    def _advance(self) -> None:
        sim = self.sim
        dt = self.scene.time.dt or sim.stable_time_step(self.scene.time.cfl)
        # land exactly on output times and on the end time
        to_frame = self.frames.until_next(sim.time)
        self.dt = min(dt, to_frame) if to_frame > TIME_TOLERANCE * dt else dt
        sim.advance(self.dt)

    def release(self) -> None:
        """Let the simulation's arrays go (the run has ended), keeping its step, time and domain."""
        self.sim = _Ended(self.sim.step_count, self.sim.time, self.sim.domain)
        gc.collect()   # its phases and hooks hold it (cycles): collected now, not at the collector's leisure

    def report(self, now: float, stage: str = "stepping") -> None:
        if self.progress is not None and self.sim.domain.is_root:
            self.rates.update(now, self.sim.step_count, self.sim.time)
            info = _progress(self.sim, self.end, self.dt, self.rates, self.last_energies)
            info.stage = stage
            self.progress(info)


def make_simulation(scene: Scene) -> ExplicitMPM:
    """The particles, grid and step of a validated scene, at t = 0."""
    return ExplicitMPM(scene)


def _series_stride(scene, sim: ExplicitMPM) -> int:
    """Energies every N steps: the scene's N, or every step up to MAX_SERIES_POINTS points."""
    energies = scene.output.energies
    if energies is False:
        return 2**62
    if energies is not True:
        return int(energies)
    dt = scene.time.dt or sim.stable_time_step(scene.time.cfl)
    return max(1, math.ceil(scene.time.end / dt / MAX_SERIES_POINTS))


def _progress(sim: ExplicitMPM, end: float, dt: float, rates: RateMeter, energies: dict) -> ProgressInfo:
    fraction = min(1.0, sim.time / end) if end > 0 else 1.0
    eta = 0.0 if fraction >= 1.0 else rates.eta_seconds(end - sim.time)
    return ProgressInfo(step=sim.step_count, time=sim.time, end_time=end, fraction=fraction,
                        steps_per_second=rates.steps_per_second, eta_seconds=eta, dt=dt, energies=dict(energies))


class _Compiling:
    """The run's first stage: numba loads or compiles the kernels until the first step is done.

    Counts the compilations (Result.compiled) and, for a cold variant, starts the helper
    that compiles the step from its other end (solver/precompile.py) once the simulation
    knows its thread count, which decides the kernels' forms (solver/jit.py). With a progress
    callback, a thread reports stage "compiling" every REPORT_S with an ETA of the
    compilation left (the cost model's figure, solver/cost.py) plus the run's estimate,
    since the main thread is in the compiler and reports nothing. After the first step the
    variant is marked compiled, so that later estimates leave the compilation out."""

    REPORT_S = 1.0

    def __init__(self, scene: Scene, started: float, progress):
        self.scene, self.started, self.progress = scene, started, progress
        self.meter = CompileMeter()
        self.helper = None
        self.threads = 0   # the simulation's, once it is built
        self.active = True
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._report, daemon=True) if progress is not None else None

    def __enter__(self) -> "_Compiling":
        self.meter.__enter__()
        if self._thread is not None:
            self._thread.start()
        return self

    def start_helper(self, threads: int) -> None:
        self.threads = threads
        self.helper = precompile.start(self.scene, threads)   # a cold variant on a machine with a core to spare

    def __exit__(self, *exc) -> None:
        self.done()
        self.meter.__exit__(*exc)

    def done(self) -> None:
        if not self.active:
            return
        self.active = False
        precompile.stop(self.helper)
        self._stop.set()
        if self._thread is not None:
            self._thread.join()
        if self.meter.count and self.threads:
            cost.mark_compiled(self.scene, self.threads, self.meter.seconds, self.meter.count)

    def _report(self) -> None:
        from solver.summary import summarize   # counts the particles: here, beside the compiler
        try:
            summary = summarize(self.scene)
            compiling, total = summary.estimated_compile_seconds, summary.estimated_run_seconds
        except Exception:   # an estimate is a courtesy: never the run's failure
            compiling = total = None
        while True:
            elapsed = wallclock.perf_counter() - self.started
            eta = None if total is None else total - compiling + max(compiling - elapsed, 0.0)
            self.progress(ProgressInfo(step=0, time=0.0, end_time=self.scene.time.end, fraction=0.0,
                                       steps_per_second=None, eta_seconds=eta, dt=0.0, stage="compiling"))
            if self._stop.wait(self.REPORT_S):
                return
