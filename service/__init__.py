"""The HTTP service: FastAPI app (`service.app`), job routes, scene validation,
the embedded Redis and `mpm serve`. Job records, the job store and the settings it
shares with the workers are in `core`."""
