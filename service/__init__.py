"""The HTTP service: FastAPI app (`service.app`), job routes, scene validation,
the embedded Redis and `mpm serve`. Settings and job records are in `worker`."""
