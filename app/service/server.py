"""The ASGI application of ``twin serve``: the API, the web page, the executor, all in one process."""

from __future__ import annotations

import logging
from contextlib import asynccontextmanager
from dataclasses import dataclass
from pathlib import Path

from fastapi import FastAPI, Request
from fastapi.responses import JSONResponse, RedirectResponse
from fastapi.staticfiles import StaticFiles

from app.service import api, web
from app.service.auth import AuthError
from app.service.executor import Executor
from app.service.registry import Registry
from app.service.submission import remove_staging_leftovers

#: Largest spec accepted [bytes]: the thesis study is 17 kB; a spec 15 times larger is a mistake, not a study.
MAX_SPEC_BYTES = 256 * 1024
STATIC = Path(__file__).parent / "static"

_log = logging.getLogger("benchtwin.service")


@dataclass
class Settings:
    """What ``twin serve`` was told."""

    data: Path
    workers: int = 2
    scheduler: str | None = None
    max_spec_bytes: int = MAX_SPEC_BYTES
    start_executor: bool = True


def create_app(settings: Settings) -> FastAPI:
    """The application serving data directory ``settings.data``."""
    registry = Registry(settings.data)
    executor = Executor(registry, workers=settings.workers, scheduler=settings.scheduler)

    @asynccontextmanager
    async def lifespan(app: FastAPI):
        remove_staging_leftovers(settings.data)
        if settings.start_executor:
            executor.start()
        _log.info("serving %s", settings.data)
        yield
        if settings.start_executor:
            executor.stop()

    app = FastAPI(
        title="BenchTwin robustness service",
        version="1",
        description="Monte Carlo campaigns of the BenchTwin ball-screw bench twin: submit, watch, read.",
        openapi_url="/api/v1/openapi.json",
        docs_url=None,  # the interactive pages load scripts from a CDN; nothing here comes from outside the machine
        redoc_url=None,
        lifespan=lifespan,
    )
    app.state.registry = registry
    app.state.executor = executor
    app.state.settings = settings

    @app.exception_handler(AuthError)
    async def auth_failed(request: Request, exc: AuthError):
        if request.url.path.startswith("/api/"):
            headers = {"WWW-Authenticate": "Bearer"} if exc.status == 401 else {}
            return JSONResponse({"detail": str(exc)}, status_code=exc.status, headers=headers)
        if exc.status == 401:
            return RedirectResponse(f"/login?next={request.url.path}", status_code=303)
        return web.forbidden(request, str(exc))

    @app.middleware("http")
    async def security_headers(request: Request, call_next):
        response = await call_next(request)
        response.headers.setdefault("Content-Security-Policy",
                                    "default-src 'self'; img-src 'self' data:; style-src 'self' 'unsafe-inline'; "
                                    "frame-ancestors 'none'")
        response.headers.setdefault("X-Content-Type-Options", "nosniff")
        response.headers.setdefault("Referrer-Policy", "same-origin")
        return response

    app.include_router(api.router)
    app.include_router(web.router)
    app.mount("/static", StaticFiles(directory=STATIC), name="static")
    return app
