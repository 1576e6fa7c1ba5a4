"""The workers: the Celery app and its one task, the solver runner, and what the API
shares with them (settings from `MPM_*`, job records in Redis, JSON logs)."""
