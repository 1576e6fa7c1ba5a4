"""`mpm serve`: the API and dashboard, one worker, and an embedded Redis when
MPM_REDIS_URL is not set. Ctrl-C (or SIGTERM) stops all of it: the API first, then
the worker (a running job goes back to the queue), then the embedded Redis."""
from __future__ import annotations

import argparse
import logging
import os
import signal
import subprocess
import sys

import uvicorn

from service.app import create_app
from service.auth import TokenError, access_notice, load_tokens
from service.embedded_redis import EmbeddedRedis
from worker.runner import die_with_parent
from worker.logs import configure_logging
from worker.settings import get_settings

log = logging.getLogger("mpm.serve")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--host", default=None, help="address to listen on (default MPM_HOST, 127.0.0.1)")
    parser.add_argument("--port", type=int, default=None, help="port (default MPM_PORT, 8000)")
    parser.add_argument("--no-worker", action="store_true",
                        help="API only; workers run elsewhere (`mpm worker`) on MPM_REDIS_URL")
    parser.add_argument("--access-log", action="store_true", help="log every request")


def register_serve(subparsers) -> None:
    parser = subparsers.add_parser(
        "serve", help="run the service: API, dashboard, a worker, and Redis if none is configured",
        description="Serve the HTTP API and the dashboard. Without MPM_REDIS_URL an embedded Redis "
                    "is started (data under MPM_DATA_DIR) and stopped on exit.")
    add_arguments(parser)
    parser.set_defaults(func=serve_command)


def _stop_worker(process: subprocess.Popen, timeout: float) -> None:
    if process.poll() is not None:
        return
    process.send_signal(signal.SIGTERM)  # warm shutdown: a running job is requeued
    try:
        process.wait(timeout)
    except subprocess.TimeoutExpired:
        log.warning("worker did not stop in time; killed", extra={"pid": process.pid})
        process.kill()
        process.wait()


def _interrupt(signum, frame) -> None:
    raise KeyboardInterrupt


def serve_command(args: argparse.Namespace) -> int:
    # SIGTERM (docker stop, a supervisor) stops in order like Ctrl-C. uvicorn handles both
    # while it serves, then raises the signal again: it lands here, not in the default
    # handler that would end the process before the worker and Redis are stopped.
    signal.signal(signal.SIGTERM, _interrupt)
    settings = get_settings()
    updates = {k: v for k, v in (("host", args.host), ("port", args.port)) if v is not None}
    settings = settings.model_copy(update=updates)
    configure_logging(settings.log_level)
    try:
        tokens = load_tokens(settings.api_tokens)
    except TokenError as exc:
        print(f"mpm serve: {exc}", file=sys.stderr)
        return 1
    embedded: EmbeddedRedis | None = None
    worker: subprocess.Popen | None = None
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
            # Its own session: a Ctrl-C reaches `mpm serve` only, which stops the worker in order.
            worker = subprocess.Popen([sys.executable, "-m", "worker"], env=env,
                                      start_new_session=True, preexec_fn=die_with_parent)
        elif embedded:
            log.warning("no worker: jobs stay queued (the embedded Redis is private to this process)")
        print(f"MPM service on http://{settings.host}:{settings.port}  (API docs: /docs; Ctrl-C stops)\n"
              f"{access_notice(tokens, settings.host)}", file=sys.stderr, flush=True)
        config = uvicorn.Config(create_app(settings), host=settings.host, port=settings.port,
                                log_config=None, access_log=args.access_log)
        uvicorn.Server(config).run()
    except KeyboardInterrupt:
        pass
    finally:
        if worker is not None:
            _stop_worker(worker, timeout=settings.cancel_grace_seconds + 20)
        if embedded is not None:
            embedded.stop()
    log.info("service stopped")
    return 0
