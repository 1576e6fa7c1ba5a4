"""Job ids and the files of a job. Every path is built from a validated id."""
from __future__ import annotations

import uuid
from pathlib import Path


class InvalidJobId(ValueError):
    """The text is not a job id (a canonical UUID)."""


def new_job_id() -> str:
    return str(uuid.uuid4())


def parse_job_id(text: str) -> str:
    """The canonical form of a job id, or InvalidJobId: nothing else reaches a path."""
    try:
        value = uuid.UUID(text)
    except (ValueError, TypeError, AttributeError):
        raise InvalidJobId(f"not a job id: {text!r}") from None
    if str(value) != text.lower():  # refuse braces, urn: prefixes, missing dashes
        raise InvalidJobId(f"not a job id: {text!r}")
    return str(value)


class JobFiles:
    """The folder of one job: `<jobs_dir>/<uuid>/`."""

    def __init__(self, jobs_dir: Path, job_id: str):
        self.dir = Path(jobs_dir) / parse_job_id(job_id)
        self.scene = self.dir / "scene.json"
        self.result = self.dir / "result.h5"
        self.xdmf = self.dir / "result.xdmf"
        self.log = self.dir / "solver.log"
        self.previews = self.dir / "previews"

    def redact(self, text: str) -> str:
        """`text` (a log line, an error) without the server's paths: the job's folder becomes
        `<job>` and the data folder above it `<data>` (clients see no absolute path)."""
        text = text.replace(str(self.dir.resolve()), "<job>").replace(str(self.dir), "<job>")
        data = self.dir.parent.parent
        return text.replace(str(data.resolve()), "<data>").replace(str(data), "<data>")

    def preview(self, frame: int, field: str) -> Path:
        """A cached rendering; `field` must already be checked against the known names."""
        return self.previews / f"frame{frame}_{field}.png"

    def animation(self, field: str, suffix: str) -> Path:
        """A cached animation (suffix ".gif" or ".mp4"); `field` already checked."""
        return self.previews / f"animation_{field}{suffix}"
