"""Job records in Redis: a hash per job, a sorted index by creation time (all jobs,
and one per status), a lease per running job, and the workers' heartbeats.

Every change of status is one Lua script, so that it is atomic: a job is never
both cancelled and running, never counted twice, never half-created. Field values
are stored JSON-encoded, so a record reads back with its types; their names are
those of core.models.JobRecord.
"""
from __future__ import annotations

import base64
import json
import time
from dataclasses import dataclass
from datetime import datetime, timezone
from typing import Any, Iterable

import redis
import redis.asyncio

from core.models import ACTIVE, FINISHED, RECORD_FIELDS, SWEEP_FIELDS, now_iso

PREFIX = "mpm:"
ALL_INDEX = PREFIX + "jobs"
WORKERS = PREFIX + "workers"
WARMING = PREFIX + "workers:warming"   # the set of workers compiling their kernels at start
WEBHOOKS = PREFIX + "webhooks"  # deliveries due (core/webhooks.py)
# A worker beats every HEARTBEAT_INTERVAL seconds (worker/heartbeat.py); one not heard
# from for HEARTBEAT_MAX_AGE is taken as gone (`/readyz` counts the others).
HEARTBEAT_INTERVAL = 2.0
HEARTBEAT_MAX_AGE = 10.0


def job_key(job_id: str) -> str:
    return f"{PREFIX}job:{job_id}"


def status_index(status: str) -> str:
    return f"{PREFIX}jobs:{status}"


def owner_index(owner: str) -> str:
    """An owner's jobs (every status), by creation time."""
    return f"{PREFIX}owner:{owner}:jobs"


def usage_key(owner: str, day: str) -> str:
    """The particle-steps an owner was charged on a UTC day (YYYY-MM-DD)."""
    return f"{PREFIX}owner:{owner}:usage:{day}"


def sweep_key(sweep_id: str) -> str:
    return f"{PREFIX}sweep:{sweep_id}"


def sweeps_index(owner: str | None) -> str:
    """Sweeps by creation time: all of them, or one owner's."""
    return f"{PREFIX}owner:{owner}:sweeps" if owner else f"{PREFIX}sweeps"


def lease_key(job_id: str) -> str:
    return f"{PREFIX}job:{job_id}:lease"


def today() -> str:
    """The UTC date, the day of the daily quotas."""
    return datetime.now(timezone.utc).date().isoformat()


# KEYS: all index, queued index, running index, owner index, owner's usage today, sweep,
# sweeps index, owner's sweeps index, then one key per job.
# ARGV: score, max_active, owner (JSON-encoded: 'null' for the anonymous caller), quota ('1'
# to check it), owner's max active, owner's max queued, cost of all the jobs, owner's max
# cost a day, sweep id ('' for none), the sweep's pair count, its field/value pairs, then
# per job: id, pair count, field/value pairs.
# Returns '' when all are stored, else the limit that refused them (nothing is stored then).
_CREATE = """
local n = #KEYS - 8
local queued = redis.call('ZRANGE', KEYS[2], 0, -1)
local running = redis.call('ZRANGE', KEYS[3], 0, -1)
if #queued + #running + n > tonumber(ARGV[2]) then return 'max_active' end
local sweep_pairs = tonumber(ARGV[10])
local first = 11 + sweep_pairs
if ARGV[4] == '1' then
  local prefix = string.sub(KEYS[9], 1, #KEYS[9] - #ARGV[first])
  local mine_queued, mine_running = 0, 0
  for _, id in ipairs(queued) do
    if redis.call('HGET', prefix .. id, 'owner') == ARGV[3] then mine_queued = mine_queued + 1 end
  end
  for _, id in ipairs(running) do
    if redis.call('HGET', prefix .. id, 'owner') == ARGV[3] then mine_running = mine_running + 1 end
  end
  if mine_queued + mine_running + n > tonumber(ARGV[5]) then return 'owner_active' end
  if mine_queued + n > tonumber(ARGV[6]) then return 'owner_queued' end
  local used = tonumber(redis.call('GET', KEYS[5]) or '0')
  if used + tonumber(ARGV[7]) > tonumber(ARGV[8]) then return 'owner_daily' end
  redis.call('INCRBY', KEYS[5], ARGV[7])  -- not INCRBYFLOAT: Redis 6.2 crashes logging it to the AOF
  redis.call('EXPIRE', KEYS[5], 2 * 86400)
end
local score = tonumber(ARGV[1])
local i = first
for j = 1, n do
  local id, count = ARGV[i], tonumber(ARGV[i + 1])
  redis.call('HSET', KEYS[8 + j], unpack(ARGV, i + 2, i + 1 + count))
  redis.call('ZADD', KEYS[1], score + j - 1, id)
  redis.call('ZADD', KEYS[2], score + j - 1, id)
  if ARGV[3] ~= 'null' then redis.call('ZADD', KEYS[4], score + j - 1, id) end
  i = i + 2 + count
end
if ARGV[9] ~= '' then
  redis.call('HSET', KEYS[6], unpack(ARGV, 11, 10 + sweep_pairs))
  redis.call('ZADD', KEYS[7], score, ARGV[9])
  if ARGV[3] ~= 'null' then redis.call('ZADD', KEYS[8], score, ARGV[9]) end
end
return ''
"""

# KEYS: job, all index, webhook queue. ARGV: id, status-index prefix, new status, allowed
# statuses (space separated), then field/value pairs. Returns the status before (nil: no
# job); the change is made only when that status was allowed. A job that ends with a
# callback_url (or in a sweep) gets its delivery queued here (core/webhooks.py).
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
  if ARGV[3] == 'succeeded' or ARGV[3] == 'failed' or ARGV[3] == 'cancelled' then
    local t = redis.call('TIME')
    local callback = redis.call('HGET', KEYS[1], 'callback_url')
    if callback and callback ~= 'null' then redis.call('ZADD', KEYS[3], t[1], 'job|' .. ARGV[1] .. '|1') end
    local sweep = redis.call('HGET', KEYS[1], 'sweep')
    if sweep and sweep ~= 'null' then
      redis.call('ZADD', KEYS[3], t[1], 'sweep|' .. cjson.decode(sweep) .. '|1')
    end
  end
end
return current
"""

# KEYS: job, all index. ARGV: id, status-index prefix, allowed statuses, owner-index prefix.
# Removes the record when its status is allowed; returns the status (nil: no job).
_DELETE = """
local raw = redis.call('HGET', KEYS[1], 'status')
if not raw then return nil end
local current = cjson.decode(raw)
for s in string.gmatch(ARGV[3], '%S+') do
  if s == current then
    local owner = redis.call('HGET', KEYS[1], 'owner')
    if owner and owner ~= 'null' then
      redis.call('ZREM', ARGV[4] .. cjson.decode(owner) .. ':jobs', ARGV[1])
    end
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
# A running job whose lease is gone lost its worker: back to queued, counted in `lost`
# (worker/tasks.py fails a job lost too often). Returns their ids.
_REQUEUE_ORPHANS = """
local out = {}
for _, id in ipairs(redis.call('ZRANGE', KEYS[1], 0, -1)) do
  if redis.call('EXISTS', ARGV[1] .. 'job:' .. id .. ':lease') == 0 then
    local score = redis.call('ZSCORE', KEYS[1], id)
    redis.call('ZREM', KEYS[1], id)
    redis.call('ZADD', KEYS[2], score, id)
    redis.call('HSET', ARGV[1] .. 'job:' .. id, 'status', '"queued"', 'started_at', 'null',
               'progress', '0.0', 'step', '0', 'stage', '"queued"')
    redis.call('HINCRBY', ARGV[1] .. 'job:' .. id, 'lost', 1)
    table.insert(out, id)
  end
end
return out
"""


@dataclass(frozen=True)
class OwnerQuota:
    """What one owner (None: the anonymous caller of a service without tokens) may have
    at once, and submit in a day (checked with the jobs' creation)."""
    owner: str | None
    max_active: int      # queued + running
    max_queued: int
    cost: int            # what these jobs are charged: particles x estimated steps
    max_daily_cost: float


@dataclass
class Page:
    jobs: list[dict[str, Any]]
    next_cursor: str | None


class CursorError(ValueError):
    """A paging cursor that this store did not hand out; `reason` says so (for an answer
    that names the cursor its own way)."""

    reason = "not a cursor from this service"

    def __init__(self) -> None:
        super().__init__(f"cursor: {self.reason}")


def _encode_cursor(score: int, job_id: str) -> str:
    return base64.urlsafe_b64encode(f"{score}:{job_id}".encode()).decode().rstrip("=")


def _decode_cursor(cursor: str) -> tuple[int, str]:
    try:
        text = base64.urlsafe_b64decode(cursor + "=" * (-len(cursor) % 4)).decode()
        score, job_id = text.split(":", 1)
        return int(score), job_id
    except (ValueError, UnicodeDecodeError):
        raise CursorError() from None


class JobStore:
    """The job records. Needs clients made with `decode_responses=True`; `async_client`
    (optional) serves `get_async`, for callers that must not block an event loop."""

    def __init__(self, client: redis.Redis, async_client: redis.asyncio.Redis | None = None):
        self.redis = client
        self.async_redis = async_client
        self._create = client.register_script(_CREATE)
        self._transition = client.register_script(_TRANSITION)
        self._delete = client.register_script(_DELETE)
        self._renew = client.register_script(_RENEW)
        self._release = client.register_script(_RELEASE)
        self._requeue_orphans = client.register_script(_REQUEUE_ORPHANS)

    # -- records ---------------------------------------------------------------

    @staticmethod
    def _pairs(fields: dict[str, Any], known: frozenset[str] = RECORD_FIELDS) -> list[str]:
        unknown = fields.keys() - known
        if unknown:
            raise ValueError(f"not fields of a record (core.models): {sorted(unknown)}")
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
        return self.admit(job_id, fields, max_active) is None

    def admit(self, job_id: str, fields: dict[str, Any], max_active: int,
              quota: OwnerQuota | None = None) -> str | None:
        """Store a new queued job (of `quota.owner`, charged `quota.cost` today) unless a
        limit refuses it. Returns None, or which limit: "max_active" (the service's),
        "owner_active", "owner_queued" or "owner_daily"."""
        return self.admit_all({job_id: fields}, max_active, quota)

    def admit_all(self, jobs: dict[str, dict[str, Any]], max_active: int, quota: OwnerQuota | None = None,
                  sweep: dict[str, Any] | None = None) -> str | None:
        """Store the jobs {id: fields} (and the sweep record they make, if any), all or none:
        the limits count every one of them. Returns None or the limit, as `admit`."""
        owner = quota.owner if quota else None
        score = time.time_ns() // 1000
        limits = (["1", quota.max_active, quota.max_queued, quota.cost, repr(float(quota.max_daily_cost))]
                  if quota else ["0", 0, 0, 0, 0])
        sweep_pairs = self._pairs(sweep, SWEEP_FIELDS) if sweep else []
        args: list[Any] = [score, max_active, json.dumps(owner), *limits,
                           sweep["id"] if sweep else "", len(sweep_pairs), *sweep_pairs]
        for job_id, fields in jobs.items():
            pairs = self._pairs({**fields, "id": job_id, "status": "queued", "owner": owner})
            args += [job_id, len(pairs), *pairs]
        sweep_id = sweep["id"] if sweep else "-"
        refused = self._create(
            keys=[ALL_INDEX, status_index("queued"), status_index("running"), owner_index(owner or ""),
                  usage_key(owner or "", today()), sweep_key(sweep_id), sweeps_index(None),
                  sweeps_index(owner), *map(job_key, jobs)],
            args=args)
        return refused or None

    def usage_today(self, owner: str) -> float:
        return float(self.redis.get(usage_key(owner, today())) or 0)

    def get(self, job_id: str) -> dict[str, Any] | None:
        return self.decode(self.redis.hgetall(job_key(job_id)))

    async def get_async(self, job_id: str) -> dict[str, Any] | None:
        """`get` through the async client (a store made without one cannot answer it)."""
        if self.async_redis is None:
            raise RuntimeError("this JobStore has no async client")
        return self.decode(await self.async_redis.hgetall(job_key(job_id)))

    def transition(self, job_id: str, allowed: Iterable[str], to: str,
                   **fields: Any) -> str | None:
        """Set `fields` and the status `to` if the status is one of `allowed`.

        Returns the status before the call (None: no such job); the caller compares
        it with `allowed` to know whether the change was made."""
        return self._transition(
            keys=[job_key(job_id), ALL_INDEX, WEBHOOKS],
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
                            args=[job_id, PREFIX + "jobs:", " ".join(allowed), PREFIX + "owner:"])

    def count_active(self) -> int:
        return sum(self.redis.zcard(status_index(s)) for s in ACTIVE)

    def list(self, status: str | None = None, limit: int = 50, cursor: str | None = None,
             owner: str | None = None) -> Page:
        """Newest first, `limit` at a time; `cursor` is the previous page's `next_cursor`.
        With `owner`, only that owner's jobs (read from the owner's index, filtered by status)."""
        after = _decode_cursor(cursor) if cursor else None
        if owner is None:
            index, wanted = (status_index(status) if status else ALL_INDEX), None
        else:
            index, wanted = owner_index(owner), status
        kept: list[tuple[dict[str, Any], int]] = []
        while len(kept) <= limit:
            rows = self._rows_after(index, after, limit + 1)
            pipe = self.redis.pipeline(transaction=False)
            for job_id, _ in rows:
                pipe.hgetall(job_key(job_id))
            for (_, score), job in zip(rows, map(self.decode, pipe.execute())):
                if job and (wanted is None or job["status"] == wanted):
                    kept.append((job, score))
            if len(rows) <= limit:  # the index has no more
                break
            after = (rows[-1][1], rows[-1][0])
        next_cursor = _encode_cursor(kept[limit - 1][1], kept[limit - 1][0]["id"]) if len(kept) > limit else None
        return Page([job for job, _ in kept[:limit]], next_cursor)

    def _rows_after(self, index: str, after: tuple[int, str] | None, count: int) -> list[tuple[str, int]]:
        """Up to `count` (id, score) of `index` that come after `after` (newest first)."""
        top: str | int = "+inf"
        extra = 0
        if after:
            top = after[0]
            # Jobs created in the same microsecond share a score: fetch them all, then
            # keep only those after the cursor in (score, id) descending order.
            extra = self.redis.zcount(index, top, top)
        rows = self.redis.zrevrangebyscore(index, top, "-inf", start=0, num=count + extra, withscores=True)
        rows = [(job_id, int(score)) for job_id, score in rows]
        if after:
            rows = [r for r in rows if (r[1], r[0]) < after]
        return rows[:count]

    # -- sweeps ------------------------------------------------------------------

    def get_sweep(self, sweep_id: str) -> dict[str, Any] | None:
        return self.decode(self.redis.hgetall(sweep_key(sweep_id)))

    def sweep_ids(self, owner: str | None, limit: int) -> list[str]:
        """The newest `limit` sweeps (of `owner` when given)."""
        return self.redis.zrevrange(sweeps_index(owner), 0, limit - 1)

    def jobs(self, job_ids: list[str]) -> list[dict[str, Any] | None]:
        """Several records in one round trip (None where a job is gone)."""
        pipe = self.redis.pipeline(transaction=False)
        for job_id in job_ids:
            pipe.hgetall(job_key(job_id))
        return [self.decode(raw) for raw in pipe.execute()]

    def delete_sweep(self, sweep_id: str, owner: str | None) -> None:
        """The sweep's record (its jobs are deleted one by one, as any job)."""
        pipe = self.redis.pipeline()
        pipe.delete(sweep_key(sweep_id))
        pipe.zrem(sweeps_index(None), sweep_id)
        if owner:
            pipe.zrem(sweeps_index(owner), sweep_id)
        pipe.execute()

    def ids_with_prefix(self, prefix: str, owner: str | None, limit: int = 2) -> list[str]:
        """Up to `limit` job ids starting with `prefix` (hex digits and dashes only: checked
        by the caller), of `owner` when given; ZSCAN matches on the Redis side."""
        found: list[str] = []
        for job_id, _ in self.redis.zscan_iter(owner_index(owner) if owner else ALL_INDEX,
                                               match=f"{prefix}*", count=1000):
            found.append(job_id)
            if len(found) >= limit:
                break
        return found

    # -- the lease of a running job ----------------------------------------------

    def acquire_lease(self, job_id: str, token: str, seconds: float) -> bool:
        """Only one worker runs a job: a redelivered copy finds the lease taken. Its holder
        acquires it again (a retry after Redis went away before answering)."""
        return bool(self.redis.set(lease_key(job_id), token, nx=True, px=int(seconds * 1000))
                    or self.renew_lease(job_id, token, seconds))

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
        self.redis.srem(WARMING, worker)

    def set_warming(self, worker: str, warming: bool) -> None:
        """A worker compiling its kernels before jobs need them (worker/warmup.py): it takes jobs meanwhile."""
        (self.redis.sadd if warming else self.redis.srem)(WARMING, worker)

    def warming_workers(self) -> list[str]:
        """The live workers still warming up."""
        live = set(self.live_workers())
        return sorted(worker for worker in self.redis.smembers(WARMING) if worker in live)

    def live_workers(self, max_age: float = HEARTBEAT_MAX_AGE) -> list[str]:
        return self.redis.zrangebyscore(WORKERS, time.time() - max_age, "+inf")
