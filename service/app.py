"""The FastAPI application: `/v1` routes, health, errors, and the dashboard at `/`."""
from __future__ import annotations

import logging
from contextlib import asynccontextmanager
from pathlib import Path

from fastapi import FastAPI
from fastapi.middleware.cors import CORSMiddleware
from fastapi.responses import HTMLResponse
from fastapi.staticfiles import StaticFiles

from service import errors, health, jobs, scenes, sweeps
from service.auth import TokenAuth, load_tokens
from service.body_limit import BodySizeLimit
from service.json_depth import JsonDepthLimit
from service.settings import ApiSettings, get_api_settings
from service.state import Services

log = logging.getLogger("mpm.api")

DASHBOARD = Path(__file__).resolve().parent.parent / "clients" / "web"
PLACEHOLDER = """<!doctype html><html><head><meta charset="utf-8"><title>MPM service</title></head>
<body><h1>MPM service</h1><p>The dashboard is not installed here.
The API is at <a href="/docs">/docs</a>.</p></body></html>"""


def create_app(settings: ApiSettings | None = None) -> FastAPI:
    """The app; raises service.auth.TokenError when MPM_API_TOKENS cannot be read."""
    settings = settings or get_api_settings()
    tokens = load_tokens(settings.api_tokens)

    @asynccontextmanager
    async def lifespan(app: FastAPI):
        app.state.services = Services.connect(settings)
        log.info("api started", extra={"redis": settings.redis_url.split("@")[-1],
                                       "data_dir": str(settings.data_dir)})
        yield
        await app.state.services.close()

    app = FastAPI(title="MPM simulation service", version="1", lifespan=lifespan,
                  description="Material point method simulations: submit a scene, follow the job, "
                              "download the HDF5 result and previews.")
    errors.install(app)
    app.state.tokens = tokens
    # Outermost last: CORS (preflights need no token), the token, the body size, the JSON depth.
    app.add_middleware(JsonDepthLimit, max_depth=settings.max_json_depth)
    app.add_middleware(BodySizeLimit, max_bytes=settings.max_body_bytes)
    app.add_middleware(TokenAuth, tokens=tokens)
    origins = [origin.strip() for origin in settings.cors_origins.split(",") if origin.strip()]
    if origins:
        app.add_middleware(CORSMiddleware, allow_origins=origins, allow_methods=["GET", "POST", "DELETE"],
                           allow_headers=["Authorization", "Content-Type"], max_age=600,
                           expose_headers=["X-MPM-Next-Line", "X-MPM-Job-Status"])
    app.include_router(jobs.router)
    app.include_router(sweeps.router)
    app.include_router(scenes.router)
    app.include_router(health.router)
    if (DASHBOARD / "index.html").is_file():
        app.mount("/", StaticFiles(directory=DASHBOARD, html=True), name="dashboard")
    else:
        @app.get("/", include_in_schema=False)
        def placeholder() -> HTMLResponse:
            return HTMLResponse(PLACEHOLDER)
    return app

