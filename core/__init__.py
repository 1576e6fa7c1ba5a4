"""The jobs core: what the API (`service/`) and the workers (`worker/`) both use.

The job record and its statuses (`core.models`), the job store in Redis
(`core.store`), job ids and folders (`core.paths`), the settings every process
reads (`core.settings`), the Celery app that queues jobs (`core.celery_app`),
JSON logs (`core.logs`), child processes that end with their parent
(`core.processes`) and the entry points of their `mpm` sub-commands (`core.cli`).
It imports neither `service` nor `worker`; they import it.
"""
