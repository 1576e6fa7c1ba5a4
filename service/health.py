"""Liveness and readiness."""
from __future__ import annotations

from typing import Any

import redis
from fastapi import APIRouter, Depends

from service.deps import CallerDep, ServicesDep
from service.errors import documented, error_response
from service.state import Services, services

router = APIRouter(tags=["health"])


@router.get("/healthz")
def healthz() -> dict[str, str]:
    """The API process answers."""
    return {"status": "ok"}


@router.get("/readyz", responses=documented({503: "Redis unreachable or no worker alive"}))
def readyz(svc: Services = Depends(services)) -> Any:
    """Ready to run jobs: Redis answers and at least one worker has been heard from."""
    try:
        svc.store.redis.ping()
        workers = svc.store.live_workers()
    except redis.RedisError as exc:
        return error_response(503, "not_ready", "Redis is not reachable", {"redis": str(exc)})
    if not workers:
        return error_response(503, "not_ready", "no worker is alive", {"redis": "ok", "workers": 0})
    return {"status": "ready", "redis": "ok", "workers": len(workers)}


@router.get("/v1/health", responses=documented({503: "Redis unreachable"}))
def health(svc: ServicesDep, _caller: CallerDep) -> Any:
    """The live workers, and those still compiling their kernels at start ("warming": they
    take jobs meanwhile, and a job may wait for its kernels to compile). A /v1 route: with
    tokens it needs one, as the workers' names say which hosts run them."""
    try:
        workers, warming = svc.store.live_workers(), svc.store.warming_workers()
    except redis.RedisError as exc:
        return error_response(503, "not_ready", "Redis is not reachable", {"redis": str(exc)})
    return {"redis": "ok", "workers": sorted(workers), "warming": warming}
