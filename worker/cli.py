"""`mpm worker`: a Celery worker for the Redis named by MPM_REDIS_URL."""
from __future__ import annotations

import argparse
import logging
import os
import socket
import sys
import threading

import redis

from celery.signals import worker_ready, worker_shutdown

from core.celery_app import QUEUE, enqueue, make_celery
from core.cli import subcommand
from core.logs import configure_logging
from core.settings import get_settings
from worker.disk import remove_expired
from worker.heartbeat import Heartbeat
from worker.webhooks import WebhookSender
from worker.warmup import warm_up

log = logging.getLogger("mpm.worker")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--concurrency", type=int, default=None,
                        help="jobs run at once (default MPM_WORKER_CONCURRENCY, 1)")
    parser.add_argument("--name", default=None,
                        help="worker name, unique among the workers (default mpm-<pid>@<host>)")
    parser.add_argument("--no-warmup", action="store_true",
                        help="skip compiling the solver kernels at start")


def _warm_up_behind(name: str, settings) -> None:
    """The warm-up in a thread: the worker is ready (heartbeat, jobs) while it compiles."""
    from solver.thread_count import available_cores
    from worker.tasks import get_store, job_environment

    def warming(flag: bool) -> None:
        try:
            get_store().set_warming(name, flag)
        except redis.RedisError as exc:
            log.warning("warm-up state not recorded: %s", exc, extra={"worker": name})

    job_cores = available_cores(job_environment(settings))
    threading.Thread(target=warm_up, kwargs={"warming": warming, "job_cores": job_cores}, name="mpm-warmup",
                     daemon=True).start()


def worker_command(args: argparse.Namespace) -> int:
    settings = get_settings()
    configure_logging(settings.log_level)
    if not settings.redis_url:
        print("mpm worker: set MPM_REDIS_URL to the Redis of the service "
              "(`mpm serve` starts its own worker)", file=sys.stderr)
        return 2
    name = args.name or f"mpm-{os.getpid()}@{socket.gethostname()}"
    app = make_celery(settings, include=("worker.tasks",))

    from worker.tasks import get_store  # the task module registers the task with `app`
    heartbeat = Heartbeat(get_store(), name, lambda job_id: enqueue(app, job_id),
                          sweep_every=settings.lease_seconds / 3,
                          retain=lambda: remove_expired(get_store(), settings.jobs_dir, settings.retention_days),
                          retain_every=min(3600.0, settings.retention_days * 86400 / 10))
    sender = WebhookSender(get_store(), settings)
    warm = settings.warmup and not args.no_warmup

    def on_ready(**_) -> None:
        heartbeat.start()
        sender.start()
        if warm:
            _warm_up_behind(name, settings)

    worker_ready.connect(on_ready, weak=False)
    worker_shutdown.connect(lambda **_: (heartbeat.stop(), sender.stop()), weak=False)

    worker = app.Worker(
        hostname=name, pool_cls="threads",
        concurrency=args.concurrency or settings.worker_concurrency,
        queues=[QUEUE], loglevel=settings.log_level.upper(),
        without_mingle=True, without_gossip=True, quiet=True)
    worker.start()
    log.info("worker stopped", extra={"worker": name})
    return worker.exitcode or 0


# the `mpm.commands` entry point `worker` (pyproject.toml)
register_worker = subcommand(
    "worker", add_arguments, worker_command,
    help="run a worker for the Redis in MPM_REDIS_URL",
    description="Run jobs from the queue in MPM_REDIS_URL; start any number, on any machines "
                "sharing MPM_DATA_DIR.")
