"""The API's own settings, from the environment (`MPM_*`): where `mpm serve` listens,
what a submission may ask for (scene limits, body size, JSON depth, jobs at once,
processes) and who may call it (tokens, per-owner quotas, CORS). The settings the
workers read too are core.settings.Settings, which these extend.
"""
from __future__ import annotations

import os
from functools import lru_cache

from pydantic import Field

from core.settings import Settings


def default_memory_limit() -> int:
    """Half the physical memory: a job must leave room for the API, Redis and the other jobs."""
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") // 2
    except (ValueError, OSError, AttributeError):   # not POSIX: a conservative 8 GiB
        return 8 * 2**30


class ApiSettings(Settings):
    """The shared settings and the API's, each from the environment variable `MPM_<NAME>`."""

    host: str = "127.0.0.1"
    port: int = Field(8000, ge=0, le=65535)

    # Limits checked at submission, before anything is allocated.
    max_particles: int = Field(2_000_000, gt=0)
    max_grid_nodes: int = Field(4_000_000, gt=0)
    max_steps: int = Field(10_000_000, gt=0)
    max_memory_bytes: int = Field(default_factory=lambda: default_memory_limit(), gt=0,
                                  description="the solver memory a scene may need (particles, grid, frames, "
                                              "bodies, series; solver/summary.py); default: half this "
                                              "machine's memory")
    max_body_bytes: int = Field(1_000_000, gt=0, description="largest accepted request body")
    max_concurrent_jobs: int = Field(1000, gt=0, description="queued + running jobs; more answer 429")
    max_sweep_jobs: int = Field(1000, gt=0, description="jobs (combinations) one sweep may make")
    max_processes: int = Field(default_factory=lambda: os.cpu_count() or 1, gt=0,
                               description="the most processes (MPI ranks) one job may use; default: the CPUs")

    # Access, per-owner quotas and request hardening (service/auth.py, quotas.py, json_depth.py).
    api_tokens: str | None = Field(None, description="`owner:token,...` or `@FILE` (one owner:token a "
                                                     "line); unset: no tokens, and 127.0.0.1 only")
    quota_active_jobs: int = Field(20, gt=0, description="queued + running jobs of one owner")
    quota_queued_jobs: int = Field(10, gt=0, description="queued jobs of one owner")
    quota_particle_steps_per_day: float = Field(1e12, gt=0, description="particles x estimated steps "
                                                "one owner may submit per UTC day")
    max_json_depth: int = Field(64, gt=0, description="deepest nesting of a JSON request body")
    cors_origins: str = Field("", description="comma-separated origins a browser may call the API "
                                              "from; empty: CORS off")


@lru_cache
def get_api_settings() -> ApiSettings:
    return ApiSettings()
