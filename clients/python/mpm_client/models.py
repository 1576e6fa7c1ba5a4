"""Pydantic models of what the service answers (docs/internals.md, "The job record").

The models accept keys they do not know (``extra="allow"``) so that a newer
service does not break an older SDK.
"""
from __future__ import annotations

from datetime import datetime

from pydantic import BaseModel, ConfigDict, Field

#: The states a job can end in; it never leaves one of them.
FINISHED = frozenset({"succeeded", "failed", "cancelled"})
STATUSES = ("queued", "running", "succeeded", "failed", "cancelled")


class _Open(BaseModel):
    model_config = ConfigDict(extra="allow")


class Summary(_Open):
    """What a scene implies, computed before anything is allocated."""

    particles: int | None = None
    particles_per_body: list[int] | dict[str, int] | None = None
    grid_nodes: int | None = None
    estimated_steps: int | None = None
    memory_bytes: int | None = None
    estimated_run_seconds: float | None = None


class Energies(_Open):
    kinetic: float | None = None
    strain: float | None = None
    total: float | None = None
    balance: float | None = None   # stored energy minus the work done on the bodies: constant if conserved
    error: float | None = None     # balance now minus balance at t = 0


class JobRecord(_Open):
    """One job as ``GET /v1/jobs/{id}`` answers it."""

    id: str
    name: str | None = None
    status: str
    created_at: datetime | None = None
    started_at: datetime | None = None
    finished_at: datetime | None = None
    progress: float = 0.0
    step: int = 0
    sim_time: float = 0.0
    end_time: float | None = None
    steps_per_second: float | None = None
    eta_seconds: float | None = None
    stage: str | None = None   # "queued" | "compiling" | "stepping" | "writing"
    energies: Energies = Field(default_factory=Energies)
    error: str | None = None
    processes: int | None = None
    nodes: int | None = None   # Slurm nodes its processes spread over (MPM_LAUNCHER=slurm)
    summary: Summary | None = None
    links: dict[str, str] = Field(default_factory=dict)

    @property
    def finished(self) -> bool:
        return self.status in FINISHED


class ExampleInfo(_Open):
    """One entry of ``GET /v1/examples``."""

    name: str
    title: str | None = None
    dimension: int | None = None
