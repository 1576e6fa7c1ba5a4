"""The workers (`mpm worker`): the one Celery task that runs a job, the solver runner,
the heartbeat and recovery of lost jobs, the disk limits and retention, the warm-up.
What they share with the API (job records, settings, the Celery app, logs) is in `core`."""
