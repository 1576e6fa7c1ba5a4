"""`mpm serve`: the API and dashboard, one worker, and an embedded Redis when
MPM_REDIS_URL is not set; the worker and the embedded Redis are started again when
they die (service/supervisor.py). Ctrl-C (or SIGTERM) stops all of it: the API first,
then the worker (a running job goes back to the queue), then the embedded Redis."""
from __future__ import annotations

import argparse
import logging
import os
import signal
import sys

import uvicorn

from core.cli import subcommand
from core.logs import configure_logging
from service.app import create_app
from service.auth import TokenError, access_notice, load_tokens
from service.embedded_redis import EmbeddedRedis
from service.settings import get_api_settings
from service.supervisor import ChildProcess, Supervisor

log = logging.getLogger("mpm.serve")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--host", default=None, help="address to listen on (default MPM_HOST, 127.0.0.1)")
    parser.add_argument("--port", type=int, default=None, help="port (default MPM_PORT, 8000)")
    parser.add_argument("--no-worker", action="store_true",
                        help="API only; workers run elsewhere (`mpm worker`) on MPM_REDIS_URL")
    parser.add_argument("--access-log", action="store_true", help="log every request")


def _interrupt(signum, frame) -> None:
    raise KeyboardInterrupt


def serve_command(args: argparse.Namespace) -> int:
    # SIGTERM (docker stop, a supervisor) stops in order like Ctrl-C. uvicorn handles both
    # while it serves, then raises the signal again: it lands here, not in the default
    # handler that would end the process before the worker and Redis are stopped.
    signal.signal(signal.SIGTERM, _interrupt)
    settings = get_api_settings()
    updates = {k: v for k, v in (("host", args.host), ("port", args.port)) if v is not None}
    settings = settings.model_copy(update=updates)
    configure_logging(settings.log_level)
    try:
        tokens = load_tokens(settings.api_tokens)
    except TokenError as exc:
        print(f"mpm serve: {exc}", file=sys.stderr)
        return 1
    embedded: EmbeddedRedis | None = None
    worker: ChildProcess | None = None
    supervisor = Supervisor()
    try:
        if not settings.redis_url:
            try:
                embedded = EmbeddedRedis(settings.data_dir).start()
            except RuntimeError as exc:
                print(f"mpm serve: {exc}", file=sys.stderr)
                return 1
            settings = settings.model_copy(update={"redis_url": embedded.url})
        if not args.no_worker:
            env = {**os.environ, "MPM_REDIS_URL": settings.redis_url,
                   "MPM_DATA_DIR": str(settings.data_dir)}
            worker = ChildProcess([sys.executable, "-m", "worker"], env).start()
            supervisor.watch("the worker", worker.alive, worker.start)
        elif embedded:
            log.warning("no worker: jobs stay queued (the embedded Redis is private to this process)")
        print(f"MPM service on http://{settings.host}:{settings.port}  (API docs: /docs; Ctrl-C stops)\n"
              f"{access_notice(tokens, settings.host)}", file=sys.stderr, flush=True)
        if embedded is not None:
            supervisor.watch("the embedded Redis", embedded.alive, embedded.restart)
        supervisor.start()
        config = uvicorn.Config(create_app(settings), host=settings.host, port=settings.port,
                                log_config=None, access_log=args.access_log)
        uvicorn.Server(config).run()
    except KeyboardInterrupt:
        pass
    finally:
        supervisor.stop()
        if worker is not None:
            worker.stop(timeout=settings.cancel_grace_seconds + 20)
        if embedded is not None:
            embedded.stop()
    log.info("service stopped")
    return 0


# the `mpm.commands` entry point `serve` (pyproject.toml)
register_serve = subcommand(
    "serve", add_arguments, serve_command,
    help="run the service: API, dashboard, a worker, and Redis if none is configured",
    description="Serve the HTTP API and the dashboard. Without MPM_REDIS_URL an embedded Redis "
                "is started (data under MPM_DATA_DIR) and stopped on exit.")
