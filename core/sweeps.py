"""Sweeps: a base scene and parameters (JSON pointers into it, each with its values)
make one scene per combination; the sweep's view sums its jobs' records up. The API
(service/sweeps.py) validates and stores them; the workers' webhook sender
(worker/webhooks.py) posts the view when the last job ends."""
from __future__ import annotations

import copy
import itertools
import math
from typing import Any

from core.models import ACTIVE, STATUSES
from core.store import JobStore


class PointerError(ValueError):
    """A JSON pointer that does not name a place in the scene; the message says why."""


def _tokens(pointer: str) -> list[str]:
    if not pointer.startswith("/"):
        raise PointerError("a JSON pointer starts with '/' (RFC 6901), e.g. /materials/m/youngs_modulus")
    return [token.replace("~1", "/").replace("~0", "~") for token in pointer[1:].split("/")]


def set_pointer(document: dict[str, Any], pointer: str, value: Any) -> None:
    """Set the value at `pointer`: every step but the last must exist; the last is a key
    of an object (new or not) or an existing index of an array."""
    node: Any = document
    tokens = _tokens(pointer)
    for depth, token in enumerate(tokens):
        last = depth == len(tokens) - 1
        where = "/" + "/".join(tokens[:depth]) if depth else "the scene"
        if isinstance(node, dict):
            if last:
                node[token] = value
                return
            if token not in node:
                raise PointerError(f"{where} has no {token!r}")
            node = node[token]
        elif isinstance(node, list):
            if not (token.isdigit() and int(token) < len(node)):
                raise PointerError(f"{where} is an array of {len(node)}; {token!r} is not one of its indices")
            if last:
                node[int(token)] = value
                return
            node = node[int(token)]
        else:
            raise PointerError(f"{where} is a value, not an object or an array")


def combination_count(parameters: dict[str, list[Any]], mode: str) -> int:
    """Jobs a sweep makes, from the lengths alone (before any combination is built)."""
    lengths = [len(values) for values in parameters.values()]
    return math.prod(lengths) if mode == "grid" else (lengths[0] if lengths else 0)


def combinations(parameters: dict[str, list[Any]], mode: str) -> list[dict[str, Any]]:
    """{pointer: value} of each job: every combination ("grid", the last pointer varying
    fastest) or the lists side by side ("zip", all of one length)."""
    pointers = list(parameters)
    rows = (itertools.product(*parameters.values()) if mode == "grid" else zip(*parameters.values()))
    return [dict(zip(pointers, row)) for row in rows]


def scene_of(base: dict[str, Any], combination: dict[str, Any]) -> dict[str, Any]:
    scene = copy.deepcopy(base)
    for pointer, value in combination.items():
        set_pointer(scene, pointer, value)
    return scene


def view(store: JobStore, sweep: dict[str, Any]) -> dict[str, Any]:
    """The sweep as the API answers it (and its webhook posts it): its record, the status
    counts of its jobs, their mean progress, and each job's parameters and status."""
    records = store.jobs([job["id"] for job in sweep["jobs"]])
    counts = dict.fromkeys(STATUSES, 0)
    jobs = []
    for job, record in zip(sweep["jobs"], records):
        status = record["status"] if record else "deleted"
        counts[status] = counts.get(status, 0) + 1
        jobs.append({**job, "status": status, "progress": record["progress"] if record else None,
                     "error": record.get("error") if record else None,
                     "energies": record.get("energies") if record else None,
                     "name": record.get("name") if record else None})
    total = len(jobs)
    active = sum(counts[s] for s in ACTIVE)
    progress = sum(1.0 if job["status"] not in ACTIVE else (job["progress"] or 0.0) for job in jobs) / max(1, total)
    status = "finished" if active == 0 else ("queued" if counts["queued"] == total else "running")
    shown = {k: v for k, v in sweep.items() if k not in ("owner", "notified_at")}
    return {**shown, "jobs": jobs, "status": status, "counts": counts, "progress": progress,
            "links": {"self": f"/v1/sweeps/{sweep['id']}"}}
