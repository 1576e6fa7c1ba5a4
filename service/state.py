"""What the routes share: settings, the job store, the Celery app (to enqueue)."""
from __future__ import annotations

from dataclasses import dataclass

import redis
import redis.asyncio
from celery import Celery
from fastapi import Request

from core.celery_app import make_celery
from core.disk import DiskUsage
from core.store import JobStore
from service.settings import ApiSettings


@dataclass
class Services:
    settings: ApiSettings
    store: JobStore  # with an async client too: a job's status is read without a thread hop
    celery: Celery
    disk: DiskUsage  # the jobs' folders, measured for each admission (at most every few seconds)

    @classmethod
    def connect(cls, settings: ApiSettings) -> "Services":
        options = dict(decode_responses=True, socket_timeout=5, health_check_interval=30)
        client = redis.Redis.from_url(settings.redis_url, **options)
        async_client = redis.asyncio.Redis.from_url(settings.redis_url, **options)
        return cls(settings, JobStore(client, async_client), make_celery(settings), DiskUsage(settings.jobs_dir))

    async def close(self) -> None:
        self.store.redis.close()
        await self.store.async_redis.aclose()
        self.celery.close()


def services(request: Request) -> Services:
    """FastAPI dependency."""
    return request.app.state.services
