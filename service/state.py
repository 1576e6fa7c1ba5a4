"""What the routes share: settings, the job store, the Celery app (to enqueue)."""
from __future__ import annotations

from dataclasses import dataclass

import redis
from celery import Celery
from fastapi import Request

from worker.celery_app import make_celery
from worker.settings import Settings
from worker.store import JobStore


@dataclass
class Services:
    settings: Settings
    store: JobStore
    celery: Celery

    @classmethod
    def connect(cls, settings: Settings) -> "Services":
        client = redis.Redis.from_url(settings.redis_url, decode_responses=True,
                                      socket_timeout=5, health_check_interval=30)
        return cls(settings, JobStore(client), make_celery(settings))

    def close(self) -> None:
        self.store.redis.close()
        self.celery.close()


def services(request: Request) -> Services:
    """FastAPI dependency."""
    return request.app.state.services
