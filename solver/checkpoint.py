"""Restart checkpoints: everything the time loop carries from one step to the next,
in `<out_dir>/checkpoint.h5`, so that a run stopped or killed at any moment goes on
from its last checkpoint (`mpm run --resume DIR`) and writes the same result file
as a run that was never interrupted.

A checkpoint holds
- every per-particle array (`Particles.arrays()`, the extra ones included),
- the simulation's time, step count and the work done by loads and boundary conditions,
- the loop's bookkeeping: the current dt, the next output time, how many frames and
  time-series rows were written (the rows themselves: they are small).
The frames already written are not copied into it: a resumed run takes them from the
result file it continues, which holds them (each frame is flushed when written).

It is taken at the top of a step (the state the step starts from) and written
atomically: a temporary file, flushed to disk, then renamed over the previous one.
A run that is stopped (cancel, SIGTERM) writes one where it stopped; a run that
finishes, or fails for good, removes it. Deterministic: the solver draws no random
numbers, so the same state gives the same steps, bit for bit.
"""
from __future__ import annotations

import json
import logging
import os
import time
from dataclasses import dataclass
from pathlib import Path

import h5py
import numpy as np

from solver import energy
from solver.errors import SolverError
from solver.results import RESULT_FILE, ResultWriter, list_frames

CHECKPOINT_FILE = "checkpoint.h5"
FORMAT = "mpm-checkpoint"
FORMAT_VERSION = 1
# A resumed run moves the result file it continues here while it copies its frames.
RESUME_SOURCE = ".result-before-resume.h5"
# Without a scene key or an explicit interval: one checkpoint a minute of wall time.
DEFAULT_EVERY_SECONDS = 60.0

log = logging.getLogger("mpm.solver")


class CheckpointError(SolverError, ValueError):
    """A checkpoint that cannot be used for this run."""


@dataclass
class Policy:
    """When to write a checkpoint: every N steps and/or every M seconds of wall time."""

    every_steps: int | None = None
    every_seconds: float | None = DEFAULT_EVERY_SECONDS

    @classmethod
    def of(cls, scene, every_seconds: float | None = None) -> "Policy":
        """The scene's `output.checkpoint` when given, else `every_seconds` (or the default)."""
        chosen = scene.output.checkpoint
        if chosen is not None:
            return cls(chosen.every_steps, chosen.every_seconds)
        return cls(None, every_seconds or DEFAULT_EVERY_SECONDS)


@dataclass
class Restart:
    """A loaded checkpoint: where the loop goes on from."""

    step: int
    time: float
    dt: float
    frame_next: int
    frames_written: int
    work: dict[str, float]       # the work terms' totals over the processes, by name (energy.WorkLedger)
    particles: dict[str, np.ndarray]
    series: dict[str, np.ndarray]
    boundary_heat: float = 0.0   # heat in through heat_flux and convection faces (solver/thermal.py)
    tools: dict[str, np.ndarray] | None = None   # where the tools are (solver/tools.py's state())
    derived: tuple[str, ...] = ()   # the particle arrays that were a function of the state (Particles.derived)
    # each material's wave speed, its largest over the processes: the next time step's, where it
    # follows the state (a gas's sound speed, an EOS, Cam-Clay's p'), not the one it started with
    wave_speeds: dict[str, float] | None = None


def checkpoint_path(out_dir: str | os.PathLike) -> Path:
    return Path(out_dir) / CHECKPOINT_FILE


def scene_of(out_dir: str | os.PathLike) -> str:
    """The scene (JSON text) of the run whose checkpoint is in `out_dir`."""
    path = checkpoint_path(out_dir)
    if not path.exists():
        raise CheckpointError(f"no checkpoint in {out_dir} ({CHECKPOINT_FILE})")
    with h5py.File(path, "r", locking=False) as h5:
        return str(h5.attrs["scene"])


class Checkpointer:
    """Called at the top of every step; writes a checkpoint when one is due."""

    def __init__(self, out_dir: Path, scene, policy: Policy, writer: ResultWriter,
                 restart: Restart | None = None):
        self.path = checkpoint_path(out_dir)
        self.scene_json = scene.model_dump_json()
        self.policy = policy
        self.writer = writer
        if restart is not None and isinstance(writer, ResultWriter):   # the process that writes the file
            _carry_over(writer, Path(out_dir) / RESUME_SOURCE, restart)
        self.last_step = restart.step if restart else 0
        self.last_time = time.monotonic()
        self._mark: tuple[float, int, int, int] | None = None

    def top_of_step(self, sim, dt: float, frame_next: int) -> None:
        """Remember the state the step starts from; write it when a checkpoint is due."""
        self._mark = (dt, frame_next, self.writer.frame_count, self.writer.series_count)
        every_steps, every_seconds = self.policy.every_steps, self.policy.every_seconds
        due = ((every_steps and sim.step_count - self.last_step >= every_steps)
               or (every_seconds and time.monotonic() - self.last_time >= every_seconds))
        if sim.domain.root_says(due):    # with several processes: on rank 0's clock, all together
            self.save(sim)

    def save(self, sim) -> None:
        """Write the state of the last `top_of_step`: the loop has not changed the
        simulation since (frames and rows written after it are left out)."""
        dt, frame_next, frames_written, rows = self._mark
        particles = sim.domain.gather(sim.particles.arrays())   # all processes' particles, on rank 0
        heat = sim.thermal_series()   # (collective: every process sums its boundary heat)
        work = sim.work.totals(sim.domain)   # (collective too: each process holds its share)
        tools = sim.tools.state() if sim.tools is not None else None   # (collective too)
        speeds = _wave_speeds(sim)   # (collective too)
        self.last_step, self.last_time = sim.step_count, time.monotonic()
        if particles is None:
            return
        tmp = self.path.with_name(f".{CHECKPOINT_FILE}.{os.getpid()}.tmp")
        try:
            with h5py.File(tmp, "w", locking=False) as h5:
                h5.attrs.update(format=FORMAT, format_version=FORMAT_VERSION, scene=self.scene_json,
                                step=sim.step_count, time=sim.time, dt=dt, frame_next=frame_next,
                                frames_written=frames_written, **work,
                                **({"boundary_heat": heat["boundary_heat"]} if heat else {}),
                                derived=",".join(sim.particles.derived_names), wave_speeds=json.dumps(speeds))
                for name, values in (tools or {}).items():
                    h5.create_dataset(f"tools/{name}", data=values)
                for name, array in particles.items():
                    h5.create_dataset(f"particles/{name}", data=array)
                for name, values in self.writer.series().items():
                    h5.create_dataset(f"series/{name}", data=values[:rows])
            with open(tmp, "rb+") as f:  # on disk before it replaces the previous one
                os.fsync(f.fileno())
            os.replace(tmp, self.path)
        except BaseException:
            tmp.unlink(missing_ok=True)
            raise

    def finish(self, sim, reason: str) -> None:
        """A stopped run keeps a checkpoint where it stopped; any other end removes it."""
        if reason == "cancelled" and self._mark is not None:
            self.save(sim)
        elif sim.domain.is_root:
            self.path.unlink(missing_ok=True)


def resume(sim, out_dir: Path) -> Restart | None:
    """Continue from the checkpoint in `out_dir`: its state goes into `sim` (freshly
    built from the same scene) and the result file is set aside for `Checkpointer` to
    copy its frames from. None when there is no usable checkpoint: start from the beginning."""
    restart = load(Path(out_dir), sim.scene)
    if restart is not None:
        _restore(sim, restart)
        sim.domain.barrier()         # every process has read the result file before it moves
        if sim.domain.is_root:
            _set_aside_result(Path(out_dir))
    return restart


def load(out_dir: Path, scene) -> Restart | None:
    """The checkpoint in `out_dir`, when there is one and the result file it continues
    holds its frames; None (start from the beginning) otherwise.

    Raises CheckpointError when the checkpoint is of another scene."""
    path = checkpoint_path(out_dir)
    if not path.exists():
        return None
    try:
        with h5py.File(path, "r", locking=False) as h5:
            attrs = dict(h5.attrs)
            if attrs.get("format") != FORMAT or attrs.get("format_version") != FORMAT_VERSION:
                raise OSError(f"not a checkpoint of format {FORMAT} {FORMAT_VERSION}")
            particles = _read_group(h5["particles"])
            series = _read_group(h5["series"]) if "series" in h5 else {}
            tools = _read_group(h5["tools"]) if "tools" in h5 else None
    except (OSError, KeyError) as exc:
        log.warning("checkpoint %s unreadable (%s): starting from the beginning", path, exc)
        return None
    if json.loads(str(attrs["scene"])) != json.loads(scene.model_dump_json()):
        raise CheckpointError(f"the checkpoint in {out_dir} is of another scene")
    restart = Restart(step=int(attrs["step"]), time=float(attrs["time"]), dt=float(attrs["dt"]),
                      frame_next=int(attrs["frame_next"]), frames_written=int(attrs["frames_written"]),
                      work=_work_totals(attrs, scene), particles=particles, series=series,
                      boundary_heat=float(attrs.get("boundary_heat", 0.0)), tools=tools,
                      derived=tuple(name for name in str(attrs.get("derived", "")).split(",") if name),
                      wave_speeds=json.loads(str(attrs.get("wave_speeds", "null"))))
    source = _result_to_continue(Path(out_dir))
    try:
        complete = len(list_frames(source)) if source else 0
    except (OSError, ValueError) as exc:
        log.warning("result file %s unreadable (%s): starting from the beginning", source, exc)
        return None
    if complete < restart.frames_written:
        log.warning("result file has %d of the checkpoint's %d frames: starting from the beginning",
                    complete, restart.frames_written)
        return None
    return restart


# a work term's attribute in checkpoints written before the WorkLedger kept it by its term's name
_EARLIER_NAMES = {"pore_pressure_work": "pore_work"}


def _work_totals(attrs: dict, scene) -> dict[str, float]:
    """The scene's work terms' totals, each an attribute of its term's name."""
    names = [t.name for t in energy.terms(scene) if t.kind == energy.WORK]
    return {name: float(attrs.get(name, attrs.get(_EARLIER_NAMES.get(name, name), 0.0))) for name in names}


def _read_group(group: h5py.Group) -> dict[str, np.ndarray]:
    out: dict[str, np.ndarray] = {}
    group.visititems(lambda name, item: out.__setitem__(name, item[()])
                     if isinstance(item, h5py.Dataset) else None)
    return out


def _result_to_continue(out_dir: Path) -> Path | None:
    """The result file a resume copies its frames from: one set aside by a resume that
    did not finish copying, else the run's result file."""
    for name in (RESUME_SOURCE, RESULT_FILE):
        if (out_dir / name).exists():
            return out_dir / name
    return None


def _restore(sim, restart: Restart) -> None:
    """Put the checkpoint's state into a freshly built simulation of the same scene."""
    p = sim.particles
    for name, array in restart.particles.items():
        if name.startswith("extra/"):
            p.extra[name[len("extra/"):]] = np.ascontiguousarray(array)
        else:
            setattr(p, name, np.ascontiguousarray(array))
    # a stress the step forms from F_p is formed again, as in the run that wrote the checkpoint
    p.mark_derived(restart.derived)
    # every process read every particle, as when it seeded them: keep its slab's
    sim.domain.distribute(p)
    sim.place()
    sim.time, sim.step_count = restart.time, restart.step
    sim.work.restore(restart.work, keeps=sim.domain.is_root)   # (one process keeps each total)
    if sim.tools is not None and restart.tools is not None:
        sim.tools.restore(restart.tools, sim.domain.is_root)
    if sim.conduction is not None:   # the total, kept by one process (the series sums them)
        sim.conduction.boundary_heat = restart.boundary_heat if sim.domain.is_root else 0.0
    for name, speed in (restart.wave_speeds or {}).items():
        model = sim.material_model(name)
        if model is not None:
            model.wave_speed = speed


def _wave_speeds(sim) -> dict[str, float]:
    """Each material's wave speed now, its largest over the processes (a stress update put
    off runs first: ExplicitMPM.wave_speed)."""
    sim.wave_speed
    return {name: sim.domain.max(model.wave_speed) for name in sim.scene.materials
            if (model := sim.material_model(name)) is not None}


def _set_aside_result(out_dir: Path) -> None:
    """Move the result file being continued out of the way of the new one (once: a
    resume that stopped while copying left the source aside already)."""
    source = out_dir / RESUME_SOURCE
    if not source.exists():
        os.replace(out_dir / RESULT_FILE, source)


def _carry_over(writer: ResultWriter, source: Path, restart: Restart) -> None:
    """The new result file starts with the frames and rows written before the checkpoint."""
    writer.copy_frames(source, restart.frames_written)
    if restart.series:
        names = list(restart.series)
        for values in zip(*(restart.series[name] for name in names)):
            writer.append_series(**dict(zip(names, values)))
    source.unlink()
