"""Job records in Redis: a hash per job, a sorted index by creation time (all jobs,
and one per status), a lease per running job, and the workers' heartbeats.

Every change of status is one Lua script, so that it is atomic: a job is never
both cancelled and running, never counted twice, never half-created. Field values
are stored JSON-encoded, so a record reads back with its types.
"""
from __future__ import annotations

import base64
import json
import time
from dataclasses import dataclass
from datetime import datetime, timezone
from typing import Any, Iterable

import redis

PREFIX = "mpm:"
STATUSES = ("queued", "running", "succeeded", "failed", "cancelled")
ACTIVE = ("queued", "running")
FINISHED = ("succeeded", "failed", "cancelled")
ALL_INDEX = PREFIX + "jobs"
WORKERS = PREFIX + "workers"


def job_key(job_id: str) -> str:
    return f"{PREFIX}job:{job_id}"


def status_index(status: str) -> str:
    return f"{PREFIX}jobs:{status}"


def lease_key(job_id: str) -> str:
    return f"{PREFIX}job:{job_id}:lease"


def now_iso() -> str:
    return datetime.now(timezone.utc).isoformat(timespec="milliseconds").replace("+00:00", "Z")


# KEYS: job, all index, queued index, running index.
# ARGV: id, score, max_active, then field/value pairs. Returns 1, or 0 when over quota.
_CREATE = """
local active = redis.call('ZCARD', KEYS[3]) + redis.call('ZCARD', KEYS[4])
if active >= tonumber(ARGV[3]) then return 0 end
redis.call('HSET', KEYS[1], unpack(ARGV, 4))
redis.call('ZADD', KEYS[2], ARGV[2], ARGV[1])
redis.call('ZADD', KEYS[3], ARGV[2], ARGV[1])
return 1
"""

# KEYS: job, all index. ARGV: id, status-index prefix, new status, allowed statuses
# (space separated), then field/value pairs. Returns the status before (nil: no job);
# the change is made only when that status was allowed.
_TRANSITION = """
local raw = redis.call('HGET', KEYS[1], 'status')
if not raw then return nil end
local current = cjson.decode(raw)
local allowed = false
for s in string.gmatch(ARGV[4], '%S+') do if s == current then allowed = true end end
if not allowed then return current end
if #ARGV > 4 then redis.call('HSET', KEYS[1], unpack(ARGV, 5)) end
if ARGV[3] ~= current then
  local score = redis.call('ZSCORE', KEYS[2], ARGV[1])
  redis.call('ZREM', ARGV[2] .. current, ARGV[1])
  redis.call('ZADD', ARGV[2] .. ARGV[3], score, ARGV[1])
  redis.call('HSET', KEYS[1], 'status', cjson.encode(ARGV[3]))
end
return current
"""

# KEYS: job, all index. ARGV: id, status-index prefix, allowed statuses.
# Removes the record when its status is allowed; returns the status (nil: no job).
_DELETE = """
local raw = redis.call('HGET', KEYS[1], 'status')
if not raw then return nil end
local current = cjson.decode(raw)
for s in string.gmatch(ARGV[3], '%S+') do
  if s == current then
    redis.call('DEL', KEYS[1])
    redis.call('ZREM', KEYS[2], ARGV[1])
    redis.call('ZREM', ARGV[2] .. current, ARGV[1])
    return current
  end
end
return current
"""

# KEYS: lease. ARGV: token, milliseconds. Extends the lease only for its holder.
_RENEW = """
if redis.call('GET', KEYS[1]) == ARGV[1] then
  return redis.call('PEXPIRE', KEYS[1], ARGV[2])
end
return 0
"""

_RELEASE = """
if redis.call('GET', KEYS[1]) == ARGV[1] then return redis.call('DEL', KEYS[1]) end
return 0
"""


# KEYS: running index, queued index. ARGV: key prefix.
# A running job whose lease is gone lost its worker: back to queued. Returns their ids.
_REQUEUE_ORPHANS = """
local out = {}
for _, id in ipairs(redis.call('ZRANGE', KEYS[1], 0, -1)) do
  if redis.call('EXISTS', ARGV[1] .. 'job:' .. id .. ':lease') == 0 then
    local score = redis.call('ZSCORE', KEYS[1], id)
    redis.call('ZREM', KEYS[1], id)
    redis.call('ZADD', KEYS[2], score, id)
    redis.call('HSET', ARGV[1] .. 'job:' .. id, 'status', '"queued"', 'started_at', 'null',
               'progress', '0.0', 'step', '0')
    table.insert(out, id)
  end
end
return out
"""


@dataclass
class Page:
    jobs: list[dict[str, Any]]
    next_cursor: str | None


class CursorError(ValueError):
    """A paging cursor that this store did not hand out."""


def _encode_cursor(score: int, job_id: str) -> str:
    return base64.urlsafe_b64encode(f"{score}:{job_id}".encode()).decode().rstrip("=")


def _decode_cursor(cursor: str) -> tuple[int, str]:
    try:
        text = base64.urlsafe_b64decode(cursor + "=" * (-len(cursor) % 4)).decode()
        score, job_id = text.split(":", 1)
        return int(score), job_id
    except (ValueError, UnicodeDecodeError):
        raise CursorError("cursor: not a cursor from this service") from None


class JobStore:
    """The job records. Needs a client made with `decode_responses=True`."""

    def __init__(self, client: redis.Redis):
        self.redis = client
        self._create = client.register_script(_CREATE)
        self._transition = client.register_script(_TRANSITION)
        self._delete = client.register_script(_DELETE)
        self._renew = client.register_script(_RENEW)
        self._release = client.register_script(_RELEASE)
        self._requeue_orphans = client.register_script(_REQUEUE_ORPHANS)

    # -- records ---------------------------------------------------------------

    @staticmethod
    def _pairs(fields: dict[str, Any]) -> list[str]:
        out: list[str] = []
        for name, value in fields.items():
            out += [name, json.dumps(value)]
        return out

    @staticmethod
    def decode(raw: dict[str, str]) -> dict[str, Any] | None:
        """A record from the raw hash (as HGETALL answers it)."""
        return {k: json.loads(v) for k, v in raw.items()} if raw else None

    def create(self, job_id: str, fields: dict[str, Any], max_active: int) -> bool:
        """Store a new queued job; False when `max_active` jobs are already queued or running."""
        fields = {**fields, "id": job_id, "status": "queued"}
        score = time.time_ns() // 1000
        done = self._create(
            keys=[job_key(job_id), ALL_INDEX, status_index("queued"), status_index("running")],
            args=[job_id, score, max_active, *self._pairs(fields)])
        return bool(done)

    def get(self, job_id: str) -> dict[str, Any] | None:
        return self.decode(self.redis.hgetall(job_key(job_id)))

    def transition(self, job_id: str, allowed: Iterable[str], to: str,
                   **fields: Any) -> str | None:
        """Set `fields` and the status `to` if the status is one of `allowed`.

        Returns the status before the call (None: no such job); the caller compares
        it with `allowed` to know whether the change was made."""
        return self._transition(
            keys=[job_key(job_id), ALL_INDEX],
            args=[job_id, PREFIX + "jobs:", to, " ".join(allowed), *self._pairs(fields)])

    def update_running(self, job_id: str, **fields: Any) -> bool:
        """Progress of a running job; False when it is no longer running."""
        return self.transition(job_id, ["running"], "running", **fields) == "running"

    def request_cancel(self, job_id: str) -> str | None:
        """Cancel a queued job at once, flag a running one for its worker.

        Returns the status before (None: no such job)."""
        before = self.transition(job_id, ["queued"], "cancelled",
                                 cancel_requested=True, finished_at=now_iso())
        if before == "running":
            before = self.transition(job_id, ["running"], "running", cancel_requested=True)
        return before

    def cancel_requested(self, job_id: str) -> bool:
        raw = self.redis.hget(job_key(job_id), "cancel_requested")
        return bool(raw and json.loads(raw))

    def delete(self, job_id: str, allowed: Iterable[str] = FINISHED) -> str | None:
        """Remove the record if its status is one of `allowed` (by default: finished).

        Returns the status (None: no such job)."""
        return self._delete(keys=[job_key(job_id), ALL_INDEX],
                            args=[job_id, PREFIX + "jobs:", " ".join(allowed)])

    def count_active(self) -> int:
        return sum(self.redis.zcard(status_index(s)) for s in ACTIVE)

    def list(self, status: str | None = None, limit: int = 50, cursor: str | None = None) -> Page:
        """Newest first, `limit` at a time; `cursor` is the previous page's `next_cursor`."""
        index = status_index(status) if status else ALL_INDEX
        top: str | int = "+inf"
        skip_from: tuple[int, str] | None = None
        extra = 0
        if cursor:
            skip_from = _decode_cursor(cursor)
            top = skip_from[0]
            # Jobs created in the same microsecond share a score: fetch them all, then
            # keep only those after the cursor in (score, id) descending order.
            extra = self.redis.zcount(index, top, top)
        rows = self.redis.zrevrangebyscore(index, top, "-inf", start=0, num=limit + 1 + extra,
                                           withscores=True)
        rows = [(job_id, int(score)) for job_id, score in rows]
        if skip_from:
            rows = [r for r in rows if (r[1], r[0]) < skip_from]
        has_more = len(rows) > limit
        rows = rows[:limit]
        pipe = self.redis.pipeline(transaction=False)
        for job_id, _ in rows:
            pipe.hgetall(job_key(job_id))
        jobs = [job for job in map(self.decode, pipe.execute()) if job]
        next_cursor = _encode_cursor(rows[-1][1], rows[-1][0]) if has_more and rows else None
        return Page(jobs, next_cursor)

    # -- the lease of a running job ----------------------------------------------

    def acquire_lease(self, job_id: str, token: str, seconds: float) -> bool:
        """Only one worker runs a job: a redelivered copy finds the lease taken."""
        return bool(self.redis.set(lease_key(job_id), token, nx=True, px=int(seconds * 1000)))

    def renew_lease(self, job_id: str, token: str, seconds: float) -> bool:
        return bool(self._renew(keys=[lease_key(job_id)], args=[token, int(seconds * 1000)]))

    def release_lease(self, job_id: str, token: str) -> None:
        self._release(keys=[lease_key(job_id)], args=[token])

    def requeue_orphans(self) -> list[str]:
        """Running jobs whose lease expired (their worker died) go back to queued;
        the caller puts them on the queue again."""
        return self._requeue_orphans(keys=[status_index("running"), status_index("queued")],
                                     args=[PREFIX])

    # -- workers ---------------------------------------------------------------

    def heartbeat(self, worker: str) -> None:
        self.redis.zadd(WORKERS, {worker: time.time()})

    def worker_gone(self, worker: str) -> None:
        self.redis.zrem(WORKERS, worker)

    def live_workers(self, max_age: float) -> list[str]:
        return self.redis.zrangebyscore(WORKERS, time.time() - max_age, "+inf")
