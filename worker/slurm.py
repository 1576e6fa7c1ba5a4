"""The Slurm launcher (MPM_LAUNCHER=slurm): a job's solver run as a Slurm batch job.

Why `sbatch` and not slurmrestd: sbatch, scontrol, sacct and scancel are on
every Slurm login node and need no extra daemon, no JWT keys and no open port; the
worker only has to run where they work (a login or service node) and see the
shared folder MPM_DATA_DIR.

`SlurmLauncher.run` does for a Slurm job what `worker.runner.run_solver` does for a
child process, and answers the same `Outcome`:

- submit: a batch script written into the job's folder (`slurm.sh`, re-runnable by
  hand) runs the same `python -m solver run SCENE -o DIR --progress json -n K
  --resume DIR --checkpoint-seconds S`, with K = `"processes"` ranks over `"nodes"`
  nodes started by MPICH's mpiexec with Slurm's launcher (`-launcher slurm`: its
  proxies start as a job step with srun, one per node of the allocation). Its
  standard output (the progress lines) goes to `slurm.out`, its standard error to the
  job's log, both appended to (a requeued run adds to them). The Slurm job id is kept
  in `slurm.jobid`, so that a worker taking the job over (after a shutdown or a
  lost worker) follows the same Slurm job instead of submitting another.
- follow: `scontrol show job` (and `sacct` once slurmctld has forgotten the job)
  every poll, and the new lines of `slurm.out`: progress lines
  reach the job record as they do from a local run; while Slurm holds the job
  pending its stage is "queued".
- stop: a cancel, MPM_MAX_JOB_SECONDS or the disk quota send SIGTERM to the solver's
  processes only (`scancel --signal=TERM`: the batch shell for one rank, the ranks'
  step for several, never the srun in the batch step, which answers a SIGTERM by
  killing its ranks), so the solver ends its step and closes the result file; a
  plain `scancel` follows after MPM_CANCEL_GRACE_SECONDS if it is still there. A
  worker shutting down or losing its lease leaves the batch job running.
- preemption, requeue, time limit: Slurm's SIGTERM (a preemption's GraceTime, or
  `--signal` 120 s before the time limit) makes the solver write a checkpoint where
  it stops and end; a run that ended so, or that Slurm ended (TIMEOUT, PREEMPTED,
  NODE_FAIL), is submitted again and resumes from its checkpoint, like a solver
  process killed on a local worker (MPM_MAX_ATTEMPTS bounds both). A job that Slurm
  requeues itself (`--requeue`: `scontrol requeue`, PreemptMode=REQUEUE without
  grace, a failed node) keeps its id and is followed on; its run started again
  resumes from the last checkpoint (for several ranks the one of
  MPM_CHECKPOINT_SECONDS: that SIGTERM reaches srun, which kills the ranks).
"""
from __future__ import annotations

import logging
import shlex
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from core.paths import JobFiles
from core.settings import Settings
from worker.runner import Outcome, ProgressLine, RunControl, progress_item, tail

log = logging.getLogger("mpm.worker")

# Slurm's job states (squeue/scontrol/sacct; sacct may add " by UID" to CANCELLED).
ACTIVE_STATES = frozenset({"PENDING", "CONFIGURING", "RUNNING", "COMPLETING", "SUSPENDED", "REQUEUED",
                           "REQUEUE_FED", "REQUEUE_HOLD", "RESIZING", "SIGNALING", "STAGE_OUT",
                           "STOPPED", "RESV_DEL_HOLD", "SPECIAL_EXIT"})
# Ended before the run did, through no fault of the run: submitted again, resuming.
RESUMABLE_STATES = frozenset({"TIMEOUT", "PREEMPTED", "NODE_FAIL", "BOOT_FAIL", "DEADLINE"})


@dataclass
class SlurmState:
    state: str            # e.g. "RUNNING", "COMPLETED", "TIMEOUT"; "UNKNOWN" when Slurm has no record
    exit_code: int = 0    # the batch script's exit status
    signal: int = 0       # the signal that ended it, 0 if none
    reason: str = ""


def _run(command: list[str], env: dict[str, str] | None) -> subprocess.CompletedProcess:
    """A Slurm command; one that cannot run or hangs (a slurmctld away) answers as failed."""
    try:
        return subprocess.run(command, env=env, capture_output=True, text=True, timeout=60)
    except (OSError, subprocess.SubprocessError) as error:
        return subprocess.CompletedProcess(command, -1, "", str(error))


def parse_exit_code(text: str) -> tuple[int, int]:
    """Slurm's "EXIT:SIGNAL" (e.g. "0:0", "3:0", "0:15")."""
    code, _, sig = text.partition(":")
    try:
        return int(code or 0), int(sig or 0)
    except ValueError:
        return 0, 0


def query_state(job_id: str, env: dict[str, str] | None = None) -> SlurmState:
    """The Slurm job's state: from slurmctld (`scontrol show job`, which knows ended jobs
    for MinJobAge seconds), else from the accounting (`sacct`), else "UNKNOWN"."""
    answer = _run(["scontrol", "show", "job", "-o", job_id], env)
    if answer.returncode == 0 and "JobState=" in answer.stdout:
        fields = dict(item.split("=", 1) for item in answer.stdout.split() if "=" in item)
        code, sig = parse_exit_code(fields.get("ExitCode", "0:0"))
        return SlurmState(fields.get("JobState", "UNKNOWN"), code, sig, fields.get("Reason", ""))
    answer = _run(["sacct", "-n", "-P", "-X", "-j", job_id, "-o", "State,ExitCode"], env)
    line = answer.stdout.strip().splitlines()[-1] if answer.returncode == 0 and answer.stdout.strip() else ""
    if line:
        state, _, exit_code = line.partition("|")
        code, sig = parse_exit_code(exit_code)
        return SlurmState(state.split()[0], code, sig)
    return SlurmState("UNKNOWN")


class SlurmError(RuntimeError):
    pass


class SlurmLauncher:
    """Runs jobs as Slurm batch jobs (module docstring). One object per worker."""

    SCRIPT, STDOUT, JOB_ID = "slurm.sh", "slurm.out", "slurm.jobid"
    WARNING_SECONDS = 120   # SIGTERM this long before the time limit (Slurm's resolution: 60 s)
    UNKNOWN_SECONDS = 600   # Slurm answering nothing of the job this long: the run is taken as lost

    def __init__(self, settings: Settings, python: str | None = None, poll_interval: float = 1.0):
        self.settings = settings
        self.python = python or sys.executable   # the same environment on the nodes (shared folder)
        self.poll_interval = poll_interval

    # -- the batch script -------------------------------------------------
    def command(self, files: JobFiles, processes: int) -> list[str]:
        """The run in the allocation: the solver, under mpiexec's Slurm launcher for K > 1."""
        solver = ["-m", "solver", "run", str(files.scene), "-o", str(files.dir), "--progress", "json",
                  "-n", str(processes), "--resume", str(files.dir),
                  "--checkpoint-seconds", repr(self.settings.checkpoint_seconds)]
        if processes == 1:
            return [self.python, *solver]
        from solver.parallel.launch import mpiexec
        return [mpiexec(), "-launcher", "slurm", "-n", str(processes), self.python, "-m", "mpi4py", *solver]

    def script(self, job_id: str, files: JobFiles, processes: int, nodes: int) -> str:
        s = self.settings
        options = [f"--job-name=mpm-{job_id[:8]}", f"--ntasks={processes}", f"--nodes={min(nodes, processes)}",
                   f"--output={files.dir / self.STDOUT}", f"--error={files.log}", "--open-mode=append",
                   f"--chdir={files.dir}", "--requeue", "--export=ALL",
                   # before the time limit: a stop, a checkpoint, and a run submitted again resumes
                   f"--signal={'B:' if processes == 1 else ''}TERM@{self.WARNING_SECONDS}"]
        options += [f"--partition={s.slurm_partition}"] if s.slurm_partition else []
        options += [f"--account={s.slurm_account}"] if s.slurm_account else []
        options += [f"--time={s.slurm_time_limit}"] if s.slurm_time_limit else []
        lines = ["#!/bin/bash", f"# MPM job {job_id} (written by the worker; sbatch runs it)"]
        lines += [f"#SBATCH {option}" for option in options]
        # the run's MPI is Slurm's: none of a local launch's settings (solver/parallel/launch.py)
        lines += ["unset HYDRA_LAUNCHER MPM_CORES",
                  f"exec {shlex.join(self.command(files, processes))}", ""]
        return "\n".join(lines)

    def submit(self, job_id: str, files: JobFiles, processes: int, nodes: int,
               env: dict[str, str] | None) -> str:
        path = files.dir / self.SCRIPT
        path.write_text(self.script(job_id, files, processes, nodes))
        answer = _run(["sbatch", "--parsable", str(path)], env)
        if answer.returncode != 0:
            raise SlurmError(f"sbatch failed ({answer.returncode}): {answer.stderr.strip() or answer.stdout.strip()}")
        slurm_id = answer.stdout.strip().split(";")[0]   # "ID" or "ID;CLUSTER"
        (files.dir / self.JOB_ID).write_text(slurm_id + "\n")
        log.info("submitted to Slurm as job %s", slurm_id, extra={"job_id": job_id, "slurm_job": slurm_id})
        return slurm_id

    def attached(self, files: JobFiles, env: dict[str, str] | None) -> str | None:
        """The Slurm job of an earlier run of this job that Slurm still runs or holds."""
        try:
            slurm_id = (files.dir / self.JOB_ID).read_text().strip()
        except OSError:
            return None
        # COMPLETED too: a run that ended while no worker followed it is read, not run again
        state = query_state(slurm_id, env).state.split()[0]
        return slurm_id if slurm_id and (state in ACTIVE_STATES or state == "COMPLETED") else None

    def in_flight(self, files: JobFiles) -> bool:
        return self.attached(files, None) is not None

    def stop_leftover(self, files: JobFiles) -> None:
        slurm_id = self.attached(files, None)
        if slurm_id is not None and query_state(slurm_id).state in ACTIVE_STATES:
            log.info("cancelling Slurm job %s: its job has ended", slurm_id)
            self.cancel(slurm_id, None)

    def cancel(self, slurm_id: str, env: dict[str, str] | None) -> None:
        _run(["scancel", slurm_id], env)

    def stop(self, slurm_id: str, processes: int, env: dict[str, str] | None) -> None:
        """SIGTERM to the solver's processes only: the solver itself, the batch shell, for one;
        the ranks' step for several, not the batch step, where srun would answer a SIGTERM
        by killing the ranks (SIGKILL) before they write their last checkpoint."""
        where = ["--batch"] if processes == 1 else []
        _run(["scancel", "--signal=TERM", *where, slurm_id], env)

    # -- one run, to its end ----------------------------------------------
    def run(self, job_id: str, files: JobFiles, processes: int, nodes: int, control: RunControl) -> Outcome:
        slurm_id = self.attached(files, control.env)
        # a new submission's lines come after those of the runs before it (appended to)
        reader = _LineReader(files.dir / self.STDOUT, files.log, from_end=slurm_id is None)
        if slurm_id is not None:
            log.info("following Slurm job %s of an earlier run", slurm_id, extra={"job_id": job_id})
        else:
            try:
                slurm_id = self.submit(job_id, files, processes, nodes, control.env)
            except (SlurmError, OSError, subprocess.SubprocessError) as error:
                return Outcome(1, None, None, f"the job could not be submitted to Slurm: {error}")
        return self._follow(job_id, files, slurm_id, processes, reader, control)

    def _follow(self, job_id, files, slurm_id, processes, reader, control: RunControl) -> Outcome:
        started = time.monotonic()
        stopped: str | None = None
        term_sent_at: float | None = None
        pending: ProgressLine | None = None
        last_sent = 0.0
        last_state = ""
        state = SlurmState("UNKNOWN")
        unknown_since: float | None = None
        while True:
            for item in reader.read():
                if item.get("event") != "done":
                    pending = item
            state = query_state(slurm_id, control.env)
            if state.state != last_state:
                log.info("Slurm job %s: %s %s", slurm_id, state.state, state.reason,
                         extra={"job_id": job_id, "slurm_job": slurm_id})
                if state.state == "PENDING":
                    pending = {"stage": "queued"}
                last_state = state.state
            now = time.monotonic()
            if pending is not None and now - last_sent >= control.progress_interval:
                control.on_progress(pending)
                pending, last_sent = None, now
            if state.state == "UNKNOWN":   # a slurmctld restarting: waited out for a while
                unknown_since = unknown_since or now
                if now - unknown_since > max(self.UNKNOWN_SECONDS, 10 * self.poll_interval):
                    break
            elif state.state.split()[0] not in ACTIVE_STATES:
                break
            else:
                unknown_since = None
            reason = control.should_stop()
            if stopped is None:
                stopped = reason
                if stopped is None and control.timeout_seconds and now - started > control.timeout_seconds:
                    stopped = "timeout"
                if stopped in ("shutdown", "lease_lost"):
                    # Slurm runs on: the worker that takes the job next follows it (slurm.jobid)
                    return Outcome(0, None, stopped, "")
                if stopped is not None:
                    log.info("stopping Slurm job %s (%s)", slurm_id, stopped, extra={"job_id": job_id})
                    self.stop(slurm_id, processes, control.env)
                    term_sent_at = now
            elif term_sent_at is not None and now - term_sent_at > self.settings.cancel_grace_seconds:
                log.info("cancelling Slurm job %s", slurm_id, extra={"job_id": job_id})
                self.cancel(slurm_id, control.env)   # SIGTERM to all, SIGKILL after Slurm's KillWait
                term_sent_at = None
            time.sleep(self.poll_interval)
        for item in reader.read():   # the last lines, written before the job ended
            if item.get("event") != "done":
                pending = item
        if pending is not None:
            control.on_progress(pending)
        return self._outcome(state, reader.done, stopped, files)

    @staticmethod
    def _outcome(state: SlurmState, done: ProgressLine | None, stopped: str | None, files: JobFiles) -> Outcome:
        """Slurm's end of the job, as the task reads a local run's end."""
        name = state.state.split()[0]
        log_tail = tail(files.log)
        if stopped is not None:   # we cancelled it: the task says why
            return Outcome(-signal.SIGTERM, done, stopped, log_tail)
        if name == "COMPLETED":
            return Outcome(0, done, None, log_tail)
        if name in RESUMABLE_STATES:   # submitted again by the task, from the checkpoint
            return Outcome(-signal.SIGTERM, done, None, log_tail, lost_why=f"Slurm ended it ({name})")
        if done is not None and done.get("reason") == "cancelled" and name != "CANCELLED":
            # stopped by a signal that the service did not send: Slurm's, before a time limit
            # (--signal) or a preemption's grace time; it wrote a checkpoint where it stopped
            return Outcome(-signal.SIGTERM, done, None, log_tail,
                           lost_why=f"Slurm stopped it (SIGTERM of a preemption or its time limit; {name})")
        if name == "CANCELLED":
            why = "the Slurm job was cancelled outside the service (scancel)"
            return Outcome(1, None, None, why)
        if name == "OUT_OF_MEMORY":
            return Outcome(1, None, None, "the Slurm job ran out of memory (OUT_OF_MEMORY)")
        if name == "UNKNOWN":
            return Outcome(-signal.SIGKILL, done, None, log_tail, lost_why="Slurm lost track of it")
        code = -state.signal if state.signal else (state.exit_code or 1)
        return Outcome(code, done, None, log_tail or f"the Slurm job ended {name} (exit code {state.exit_code})")


class _LineReader:
    """The new whole lines of the batch job's standard output: JSON objects are the
    solver's progress lines (the last, {"event": "done"}, also goes to the job's log,
    as from a local run); other lines go to the log."""

    def __init__(self, path: Path, log_path: Path, from_end: bool):
        self.path, self.log_path = path, log_path
        self.offset = path.stat().st_size if from_end and path.exists() else 0
        self.done: ProgressLine | None = None

    def read(self) -> list[ProgressLine]:
        try:
            with open(self.path, "rb") as f:
                f.seek(self.offset)
                data = f.read()
        except OSError:
            return []
        end = data.rfind(b"\n") + 1
        self.offset += end
        items, to_log = [], []
        for raw in data[:end].decode(errors="replace").splitlines():
            item = progress_item(raw)
            if item is not None:
                items.append(item)
                if item.get("event") == "done":
                    self.done = item
                    to_log.append(raw)
            elif raw.strip():
                to_log.append(raw)
        if to_log:
            with open(self.log_path, "a", encoding="utf-8") as log_file:
                log_file.write("\n".join(to_log) + "\n")
        return items
