"""The Celery application: Redis as the broker, one queue, one task (`TASK_NAME`, defined
by the workers in `worker.tasks`; the API only puts jobs on the queue).

Job state lives in the job records (core.store), not in a Celery result backend.
"""
from __future__ import annotations

from celery import Celery

from core.settings import Settings

QUEUE = "mpm-jobs"
TASK_NAME = "mpm.run_job"


def make_celery(settings: Settings, include: tuple[str, ...] = ()) -> Celery:
    """The app; `include`: the modules that define its tasks (a worker's)."""
    if not settings.redis_url:
        raise RuntimeError("MPM_REDIS_URL is not set (`mpm serve` sets it for its embedded Redis)")
    app = Celery("mpm", broker=settings.redis_url, include=list(include))
    app.conf.update(
        task_default_queue=QUEUE,
        task_ignore_result=True,
        task_serializer="json",
        accept_content=["json"],
        # A job is acknowledged only when it is over, and handed to another worker
        # when its worker dies; each worker holds one job at a time and reserves no other.
        task_acks_late=True,
        task_reject_on_worker_lost=True,
        worker_prefetch_multiplier=1,
        # Longer than the longest job: only a lost worker's job is redelivered.
        broker_transport_options={"visibility_timeout": settings.visibility_timeout},
        broker_connection_retry_on_startup=True,
        # Logs go through core.logs (JSON lines), stdout stays as it is.
        worker_hijack_root_logger=False,
        worker_redirect_stdouts=False,
        worker_send_task_events=False,
        worker_enable_remote_control=False,
    )
    return app


def enqueue(app: Celery, job_id: str) -> None:
    """Put a stored job on the queue."""
    app.send_task(TASK_NAME, args=[job_id], queue=QUEUE)
