"""The task with each launcher (worker/launcher.py): the local one runs a job as before,
and the Slurm one's reading of Slurm's states, driven here by a scripted Slurm (the
real one is tests/integration/test_slurm_jobs.py): a run ended by its time limit is
submitted again and resumes, a failed batch job fails the job with its exit code, a
job whose time limits keep ending it is given up after MPM_MAX_ATTEMPTS."""
from __future__ import annotations

import json
import subprocess
import threading

import pytest
from celery.exceptions import Reject

from core.models import new_job
from core.paths import JobFiles, new_job_id
from core.settings import get_settings
from service_support import bar_1d
from worker import slurm, tasks

SCENE = bar_1d("launcher", end=0.02)


@pytest.fixture
def job(store, monkeypatch, tmp_path):
    """A queued job with its scene in its folder, a task reading this store and data dir."""
    monkeypatch.setattr(tasks, "get_store", lambda: store)
    monkeypatch.setenv("MPM_DATA_DIR", str(tmp_path))
    monkeypatch.setenv("MPM_PROGRESS_INTERVAL", "0.01")
    get_settings.cache_clear()
    job_id = new_job_id()
    files = JobFiles(get_settings().jobs_dir, job_id)
    files.dir.mkdir(parents=True)
    files.scene.write_text(json.dumps(SCENE))
    assert store.create(job_id, new_job(job_id, None, name="launcher", end_time=0.02, processes=1, summary={},
                                        nodes=2), 100)
    yield job_id, files
    get_settings.cache_clear()


def test_the_local_launcher_runs_a_job_as_before(job, store):
    job_id, files = job
    tasks.run_job(job_id)
    record = store.get(job_id)
    assert record["status"] == "succeeded", record
    assert record["step"] == 20 and record["nodes"] == 2 and files.result.exists()
    assert not (files.dir / "slurm.sh").exists()


class ScriptedSlurm:
    """sbatch, scontrol and scancel as a test writes them: each submission plays its list of
    (state, exit code, lines its output gets), one a poll, the last one for ever after;
    a scancel --signal=TERM stops the solver, a plain scancel ends the run CANCELLED."""

    def __init__(self, runs: list[list[tuple[str, str, list[dict]]]], on_poll=None):
        self.runs, self.on_poll = runs, on_poll
        self.submitted: list[str] = []
        self.cancelled: list[str] = []
        self.playing: list = []
        self.out = ""

    def __call__(self, command, env):
        name = command[0]
        if name == "sbatch":
            script = command[-1]
            self.submitted.append(open(script).read())
            self.out = script.rsplit("/", 1)[0] + "/slurm.out"
            self.playing = list(self.runs.pop(0))
            return subprocess.CompletedProcess(command, 0, f"{100 + len(self.submitted)}\n", "")
        if name == "scancel":
            self.cancelled.append(" ".join(command[1:]))
            if "--signal=TERM" in command:   # the solver stops, writes its last line, exits 3 (partial)
                self.playing = [("FAILED", "3:0", [STOPPED])]
            else:
                self.playing = [("CANCELLED", "0:15", [])]
            return subprocess.CompletedProcess(command, 0, "", "")
        if name == "scontrol":
            if self.on_poll:
                self.on_poll()
            state, exit_code, lines = self.playing.pop(0) if len(self.playing) > 1 else self.playing[0]
            with open(self.out, "a") as out:
                out.writelines(json.dumps(line) + "\n" for line in lines)
            return subprocess.CompletedProcess(
                command, 0, f"JobId={command[-1]} JobState={state} Reason=None ExitCode={exit_code} Restarts=0\n", "")
        return subprocess.CompletedProcess(command, 1, "", "no such command here")


@pytest.fixture
def scripted(monkeypatch):
    """Workers with MPM_LAUNCHER=slurm, whose Slurm commands a ScriptedSlurm answers."""
    monkeypatch.setenv("MPM_LAUNCHER", "slurm")
    monkeypatch.setenv("MPM_SLURM_PARTITION", "short")
    get_settings.cache_clear()
    original = slurm.SlurmLauncher.__init__
    monkeypatch.setattr(slurm.SlurmLauncher, "__init__",
                        lambda launcher, settings: original(launcher, settings, poll_interval=0.01))

    def make(runs, on_poll=None):
        cluster = ScriptedSlurm(runs, on_poll)
        monkeypatch.setattr(slurm, "_run", cluster)
        return cluster
    return make


PROGRESS = {"event": "progress", "step": 10, "time": 0.01, "fraction": 0.5, "stage": "stepping"}
DONE = {"event": "done", "status": "complete", "reason": "finished", "message": "", "steps": 20, "time": 0.02}
STOPPED = {"event": "done", "status": "partial", "reason": "cancelled", "message": "stopped on request at step 10",
           "steps": 10, "time": 0.01}


def test_a_run_ended_by_its_slurm_time_limit_is_submitted_again_and_resumes(job, store, scripted):
    job_id, files = job
    cluster = scripted([[("PENDING", "0:0", []), ("RUNNING", "0:0", [PROGRESS]), ("TIMEOUT", "0:15", [])],
                        [("RUNNING", "0:0", []), ("COMPLETED", "0:0", [DONE])]])
    tasks.run_job(job_id)
    record = store.get(job_id)
    assert record["status"] == "succeeded", record
    assert len(cluster.submitted) == 2, (record, cluster.submitted)
    assert record["lost"] == 1 and record["step"] == 20, record
    assert len(cluster.submitted) == 2 and not cluster.cancelled
    script = cluster.submitted[0]
    assert "#SBATCH --ntasks=1" in script and "#SBATCH --nodes=1" in script   # nodes: at most one per rank
    assert "#SBATCH --partition=short" in script and "#SBATCH --requeue" in script
    assert f"--resume {files.dir}" in script
    assert (files.dir / "slurm.jobid").read_text().strip() == "102"
    assert '"event": "done"' in files.log.read_text()


def test_a_run_stopped_by_slurms_signal_before_its_time_limit_is_submitted_again(job, store, scripted):
    job_id, _ = job
    cluster = scripted([[("RUNNING", "0:0", [PROGRESS]), ("FAILED", "3:0", [STOPPED])],
                        [("RUNNING", "0:0", []), ("COMPLETED", "0:0", [DONE])]])
    tasks.run_job(job_id)
    record = store.get(job_id)
    assert record["status"] == "succeeded" and record["lost"] == 1, record
    assert "#SBATCH --signal=B:TERM@120" in cluster.submitted[0] and len(cluster.submitted) == 2


def test_a_failed_batch_job_fails_the_job_with_its_exit_code(job, store, scripted):
    job_id, files = job

    def solver_writes_to_its_log():   # the batch job's standard error (the log is cleared before a run)
        with open(files.log, "a") as log:
            log.write("Traceback: something went wrong\n")
    scripted([[("RUNNING", "0:0", []), ("FAILED", "1:0", [])]], on_poll=solver_writes_to_its_log)
    tasks.run_job(job_id)
    record = store.get(job_id)
    assert record["status"] == "failed" and "something went wrong" in record["error"], record


def test_time_limits_ending_every_run_give_the_job_up(job, store, scripted):
    job_id, _ = job
    cluster = scripted([[("RUNNING", "0:0", []), ("TIMEOUT", "0:15", [])] for _ in range(3)])
    tasks.run_job(job_id)
    record = store.get(job_id)
    assert record["status"] == "failed" and "Slurm ended it (TIMEOUT)" in record["error"], record
    assert len(cluster.submitted) == get_settings().max_attempts


def test_a_cancel_scancels_the_batch_job(job, store, scripted):
    job_id, _ = job
    polls = []

    def cancel_on_the_third_poll():
        polls.append(1)
        if len(polls) == 3:
            store.request_cancel(job_id)
    cluster = scripted([[("RUNNING", "0:0", [PROGRESS])]], on_poll=cancel_on_the_third_poll)
    tasks.run_job(job_id)
    record = store.get(job_id)
    assert record["status"] == "cancelled" and record["step"] == 10, record
    assert cluster.cancelled == ["--signal=TERM --batch 101"]   # the solver only: it ends its step, closes its file


def _stopped_worker(job_id, store, scripted, monkeypatch, runs):
    """Run the job until the worker is stopped on the second poll of Slurm: the job is back on
    the queue and its batch job left running."""
    shutting_down = threading.Event()
    monkeypatch.setattr(tasks, "_shutting_down", shutting_down)
    polls = []

    def stop_on_the_second_poll():
        polls.append(1)
        if len(polls) == 2:
            shutting_down.set()
    cluster = scripted(runs, on_poll=stop_on_the_second_poll)
    with pytest.raises(Reject):
        tasks.run_job(job_id)
    assert store.get(job_id)["status"] == "queued" and not cluster.cancelled
    shutting_down.clear()
    cluster.on_poll = None
    return cluster


def test_the_next_worker_follows_the_batch_job_a_stopped_worker_left(job, store, scripted, monkeypatch):
    job_id, files = job
    cluster = _stopped_worker(job_id, store, scripted, monkeypatch,
                              [[("RUNNING", "0:0", [PROGRESS])] * 4 + [("COMPLETED", "0:0", [DONE])]])
    tasks.run_job(job_id)   # the next worker
    record = store.get(job_id)
    assert record["status"] == "succeeded" and record["step"] == 20, record
    assert len(cluster.submitted) == 1 and not cluster.cancelled


def test_a_job_cancelled_while_back_on_the_queue_scancels_the_batch_job_left_running(job, store, scripted,
                                                                                     monkeypatch):
    job_id, _ = job
    cluster = _stopped_worker(job_id, store, scripted, monkeypatch, [[("RUNNING", "0:0", [PROGRESS])]])
    assert store.request_cancel(job_id) == "queued"   # cancelled at once by the API
    tasks.run_job(job_id)   # the queue's copy, taken by the next worker: skipped, its batch job ended
    assert store.get(job_id)["status"] == "cancelled"
    assert cluster.cancelled == ["101"] and len(cluster.submitted) == 1


@pytest.mark.parametrize("state, exit_code, returncode, stopped, error", [
    ("COMPLETED", "0:0", 0, None, None),
    ("FAILED", "3:0", 3, None, None),
    ("FAILED", "0:9", -9, None, None),
    ("CANCELLED", "0:15", 1, None, "cancelled outside the service"),
    ("OUT_OF_MEMORY", "0:125", 1, None, "out of memory"),
    ("NODE_FAIL", "0:0", -15, None, None),
    ("PREEMPTED", "0:15", -15, None, None),
])
def test_slurm_states_map_onto_outcomes(tmp_path, state, exit_code, returncode, stopped, error):
    files = JobFiles(tmp_path, new_job_id())
    files.dir.mkdir()
    code, sig = slurm.parse_exit_code(exit_code)
    outcome = slurm.SlurmLauncher._outcome(slurm.SlurmState(state, code, sig), None, None, files)
    assert outcome.returncode == returncode and outcome.stopped == stopped
    if error:
        assert error in outcome.log_tail
    if state in slurm.RESUMABLE_STATES:
        assert outcome.lost_why == f"Slurm ended it ({state})"
