"""Python SDK for the MPM simulation service.

    from mpm_client import Client
    client = Client("http://127.0.0.1:8000")
    job = client.submit("examples/two_disks.json")
    job.wait()
    job.download("two_disks.h5")
"""
from .aio import AsyncClient, AsyncJob
from .client import Client, Job, Sweep
from .errors import (
    ApiError,
    Conflict,
    JobCancelled,
    JobFailed,
    MpmError,
    NotFound,
    QuotaExceeded,
    ServiceUnavailable,
    TooLarge,
    Unauthorized,
    ValidationFailed,
    WaitTimeout,
)
from .models import ExampleInfo, JobRecord, Summary

__all__ = [
    "ApiError", "AsyncClient", "AsyncJob", "Client", "Conflict", "ExampleInfo", "Job", "JobCancelled",
    "JobFailed", "JobRecord", "MpmError", "NotFound", "QuotaExceeded", "ServiceUnavailable", "Summary",
    "Sweep", "TooLarge", "Unauthorized", "ValidationFailed", "WaitTimeout",
]
