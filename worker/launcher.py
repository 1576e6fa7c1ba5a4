"""Where a job's solver runs (MPM_LAUNCHER): the one object worker/tasks.py calls.

- `local` (default): a child process of the worker (worker/runner.py), its ranks on
  the worker's host; `"nodes"` does not apply.
- `slurm`: a Slurm batch job (worker/slurm.py), `"processes"` ranks over `"nodes"` nodes.

Both answer `run(job_id, files, processes, nodes, control)` (a `worker.runner.RunControl`)
with a `worker.runner.Outcome`, and `in_flight(files)` / `stop_leftover(files)` for a
run that goes on without a worker (a Slurm job, after its worker stopped).
"""
from __future__ import annotations

from core.paths import JobFiles
from core.settings import Settings
from worker.runner import Outcome, RunControl, run_solver, solver_command


class LocalLauncher:
    def __init__(self, settings: Settings):
        self.settings = settings

    def in_flight(self, files: JobFiles) -> bool:
        """A run of the job goes on without this worker (none does here: the solver dies with its worker)."""
        return False

    def stop_leftover(self, files: JobFiles) -> None:
        """End a run that went on after its job ended (none does here)."""

    def run(self, job_id: str, files: JobFiles, processes: int, nodes: int, control: RunControl) -> Outcome:
        command = solver_command(files.scene, files.dir, processes,
                                 checkpoint_seconds=self.settings.checkpoint_seconds)
        return run_solver(command, files.log, on_progress=control.on_progress, should_stop=control.should_stop,
                          progress_interval=control.progress_interval,
                          grace_seconds=self.settings.cancel_grace_seconds,
                          timeout_seconds=control.timeout_seconds, env=control.env)


def launcher_for(settings: Settings):
    if settings.launcher == "slurm":
        from worker.slurm import SlurmLauncher
        return SlurmLauncher(settings)
    return LocalLauncher(settings)
