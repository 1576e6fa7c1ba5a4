"""For the quota and admission tests: an API with small quotas (with tokens, or without
for the anonymous caller) on its own Redis, with no worker, so that its jobs stay
queued unless a test moves them."""
from __future__ import annotations

import os
from pathlib import Path

import httpx
import redis

from secure_service import TOKENS, bearer
from service_support import MPM, Process, answers, free_port, wait_until

from core.store import JobStore
from service.embedded_redis import EmbeddedRedis


class QuotaApi:
    """`mpm serve --no-worker` with tokens and the quotas given, on a private Redis."""

    def __init__(self, root: Path, quotas: dict[str, str], tokens: bool = True):
        self.redis = EmbeddedRedis(root / "redis").start()
        self.store = JobStore(redis.Redis.from_url(self.redis.url, decode_responses=True))
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.data_dir = root / "data"
        env = {**{k: v for k, v in os.environ.items() if not k.startswith("MPM_")},
               "PYTHONUNBUFFERED": "1", "MPM_REDIS_URL": self.redis.url,
               "MPM_DATA_DIR": str(self.data_dir),
               **({"MPM_API_TOKENS": ",".join(f"{owner}:{token}" for owner, token in TOKENS.items())}
                  if tokens else {}),
               **quotas}
        self.api = Process("quota-api", [*MPM, "serve", "--no-worker", "--port", str(self.port)],
                           env, root).start()
        wait_until(answers(self.url, "/healthz"), 60, "the quota API", processes=(self.api,))

    def client(self, owner: str | None) -> httpx.Client:
        return httpx.Client(base_url=self.url, timeout=60, headers=bearer(owner) if owner else None)

    def stop(self) -> None:
        self.api.stop()
        self.store.redis.close()
        self.redis.stop()
