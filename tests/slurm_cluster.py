"""A one-host Slurm cluster for the tests: Debian's munged, slurmctld and slurmd (one
per node: several nodes run on this host, as Debian's Slurm is built with
multiple-slurmd support), each with its own files in a temporary folder (a munge key,
a socket, a slurm.conf named by SLURM_CONF, spool and state folders) and free ports,
so that nothing of the machine's own /etc/slurm or /run/munge is used or changed.

`SlurmCluster(folder, nodes=N).start()` starts the daemons and waits until the nodes
are idle; `.env` is what a client (sbatch, squeue, scancel, the worker) needs; `.stop()`
cancels what is left and stops them. A missing daemon raises: a test that needs
Slurm fails where Slurm is missing (scripts/dev.py installs it), it never skips.
"""
from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import time
from pathlib import Path

DAEMONS = ("munged", "slurmctld", "slurmd")
# Debian's packages: what scripts/dev.py installs (ensure_test_tools)
PACKAGES = ("munge", "slurmctld", "slurmd", "slurm-client")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _binary(name: str) -> str:
    found = shutil.which(name) or next((str(Path(d) / name) for d in ("/usr/sbin", "/sbin")
                                        if (Path(d) / name).exists()), None)
    if found is None:
        raise RuntimeError(f"{name} is not installed: `python3 scripts/dev.py test` installs Debian's "
                           f"{', '.join(PACKAGES)} (as root)")
    return found


SLURM_CONF = """\
ClusterName=mpmtest
SlurmctldHost={host}(127.0.0.1)
SlurmctldPort={ctld_port}
SlurmdPort={slurmd_port}
SlurmUser=root
SlurmdUser=root
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket={munge_socket}
StateSaveLocation={root}/state
SlurmdSpoolDir={root}/spool/%n
SlurmctldPidFile={root}/slurmctld.pid
SlurmdPidFile={root}/slurmd-%n.pid
SlurmctldLogFile={root}/slurmctld.log
SlurmdLogFile={root}/slurmd-%n.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
MpiDefault=none
ReturnToService=2
JobRequeue=1
KillWait=10
MinJobAge=600
SlurmdParameters=config_overrides
SlurmctldTimeout=30
SlurmdTimeout=30
InactiveLimit=0
{node_lines}
PreemptType=preempt/partition_prio
PreemptMode=REQUEUE
PartitionName=debug Nodes={node_names} Default=YES MaxTime=INFINITE State=UP PriorityTier=1 GraceTime=30
PartitionName=urgent Nodes={node_names} MaxTime=INFINITE State=UP PriorityTier=2 PreemptMode=OFF
"""


class SlurmCluster:
    def __init__(self, folder: Path, cpus: int = 4, nodes: int = 1):
        """`nodes` > 1: that many slurmd on this host (node names n1, n2, ...), which needs a
        Slurm built with multiple-slurmd support."""
        self.root = Path(folder)
        self.host = socket.gethostname().split(".")[0]
        self.cpus = cpus
        self.nodes = [self.host] if nodes == 1 else [f"n{i + 1}" for i in range(nodes)]
        self.conf = self.root / "slurm.conf"
        self.munge_socket = self.root / "munge" / "munge.socket"
        self.processes: dict[str, subprocess.Popen] = {}
        self.env = {**os.environ, "SLURM_CONF": str(self.conf)}

    def _write_files(self) -> None:
        for sub in ("munge", "state", "spool"):
            (self.root / sub).mkdir(parents=True, exist_ok=True)
        (self.root / "munge").chmod(0o700)
        key = self.root / "munge" / "munge.key"
        key.write_bytes(os.urandom(1024))
        key.chmod(0o600)
        if len(self.nodes) == 1:
            node_lines = f"NodeName={self.host} NodeAddr=127.0.0.1 CPUs={self.cpus} State=UNKNOWN"
        else:
            node_lines = "\n".join(f"NodeName={name} NodeHostname={self.host} NodeAddr=127.0.0.1 Port={_free_port()} "
                                   f"CPUs={self.cpus} State=UNKNOWN" for name in self.nodes)
        self.conf.write_text(SLURM_CONF.format(
            host=self.host, ctld_port=_free_port(), slurmd_port=_free_port(), root=self.root,
            munge_socket=self.munge_socket, node_lines=node_lines, node_names=",".join(self.nodes)))

    def _start(self, name: str, command: list[str]) -> None:
        log = open(self.root / f"{name}.out", "ab")
        self.processes[name] = subprocess.Popen(command, env=self.env, stdout=log, stderr=subprocess.STDOUT,
                                                stdin=subprocess.DEVNULL, start_new_session=True)
        log.close()

    def _check_alive(self) -> None:
        for name, process in self.processes.items():
            if process.poll() is not None:
                raise RuntimeError(f"{name} exited ({process.returncode}):\n{self.logs()}")

    def logs(self, chars: int = 2000) -> str:
        parts = []
        for path in sorted(self.root.glob("*.out")) + sorted(self.root.glob("*.log")):
            parts.append(f"--- {path.name}\n{path.read_text(errors='replace')[-chars:]}")
        return "\n".join(parts)

    def start(self, timeout: float = 60) -> "SlurmCluster":
        binaries = {name: _binary(name) for name in DAEMONS}
        _binary("sbatch")
        self._write_files()
        munge = self.root / "munge"
        self._start("munged", [binaries["munged"], "--foreground", "--force", f"--socket={self.munge_socket}",
                               f"--key-file={munge / 'munge.key'}", f"--pid-file={munge / 'munged.pid'}",
                               f"--seed-file={munge / 'munged.seed'}", f"--log-file={munge / 'munged.log'}"])
        self._wait(lambda: self.munge_socket.exists(), timeout, "munged's socket")
        self._start("slurmctld", [binaries["slurmctld"], "-D", "-i", "-f", str(self.conf)])
        for name in self.nodes:
            self._start(f"slurmd-{name}", [binaries["slurmd"], "-D", "-f", str(self.conf), "-N", name])
        self._wait(self._nodes_idle, timeout, "the nodes to be idle")
        return self

    def _nodes_idle(self) -> bool:
        answer = subprocess.run(["sinfo", "-h", "-N", "-o", "%N %T"], env=self.env, capture_output=True, text=True)
        states = dict(line.split() for line in answer.stdout.splitlines() if line.strip())   # a line a partition
        return answer.returncode == 0 and sorted(states) == sorted(self.nodes) and set(states.values()) == {"idle"}

    def _wait(self, predicate, timeout: float, what: str) -> None:
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            self._check_alive()
            if predicate():
                return
            time.sleep(0.2)
        raise RuntimeError(f"timed out after {timeout} s waiting for {what}\n{self.logs()}")

    def run(self, *command: str) -> str:
        return subprocess.run(command, env=self.env, capture_output=True, text=True, check=True).stdout

    def stop(self) -> None:
        if "slurmctld" in self.processes and self.processes["slurmctld"].poll() is None:
            # the jobs' processes end before their slurmd (a slurmstepd outlives a stopped slurmd)
            subprocess.run(["scancel", "--full", "--user", "root"], env=self.env, capture_output=True)
            deadline = time.monotonic() + 30
            while time.monotonic() < deadline and subprocess.run(
                    ["squeue", "-h", "-o", "%i"], env=self.env, capture_output=True, text=True).stdout.strip():
                time.sleep(0.5)
        for name in reversed(list(self.processes)):
            process = self.processes[name]
            if process.poll() is None:
                process.send_signal(signal.SIGTERM)
                try:
                    process.wait(15)
                except subprocess.TimeoutExpired:
                    os.killpg(process.pid, signal.SIGKILL)
                    process.wait()
        self.processes.clear()

    def __enter__(self) -> "SlurmCluster":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()
