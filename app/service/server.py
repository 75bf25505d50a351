"""The ASGI application of ``twin serve``: the API, the web page, the executor, all in one process."""

from __future__ import annotations

import logging
import re
from contextlib import asynccontextmanager
from dataclasses import dataclass
from pathlib import Path

from fastapi import FastAPI, Request
from fastapi.exception_handlers import http_exception_handler
from fastapi.responses import JSONResponse, RedirectResponse
from fastapi.staticfiles import StaticFiles
from starlette.exceptions import HTTPException as StarletteHTTPException
from starlette.routing import Match

from app.service import api, web
from app.service.auth import COOKIE_NAME, TOKEN_PARAMETERS, TOKEN_PREFIX, UNSAFE_METHODS, AuthError, cross_site
from app.service.executor import Executor
from app.service.registry import Registry
from app.service.submission import remove_staging_leftovers

#: Largest spec accepted [bytes]: the thesis study is 17 kB; a spec 15 times larger is a mistake, not a study.
MAX_SPEC_BYTES = 256 * 1024
#: Longest campaign accepted [h] (estimated before it is queued, :mod:`campaigns.runner.budget`): the thesis study
#: (7000 runs) takes about 1.2 h on 2 workers; a day of the team's queue is the most one campaign may take.
MAX_CAMPAIGN_HOURS = 24.0
#: Campaigns one token may have queued or running at once: a baseline and a few design variants of a review
#: fit; a script submitting in a loop stops there instead of filling the queue for everyone (admins included).
MAX_QUEUED_PER_USER = 5
STATIC = Path(__file__).parent / "static"

_log = logging.getLogger("benchtwin.service")


@dataclass
class Settings:
    """What ``twin serve`` was told."""

    data: Path
    workers: int = 2
    scheduler: str | None = None
    max_spec_bytes: int = MAX_SPEC_BYTES
    max_campaign_hours: float = MAX_CAMPAIGN_HOURS
    max_queued_per_user: int = MAX_QUEUED_PER_USER
    start_executor: bool = True


class WithoutQueryString(logging.Filter):
    """Access-log lines show the path without its query string: whatever a URL carries never reaches the log
    (a token in a URL is refused, but the request line is logged before the answer)."""

    def filter(self, record: logging.LogRecord) -> bool:
        args = record.args
        if isinstance(args, tuple) and len(args) >= 3 and isinstance(args[2], str) and "?" in args[2]:
            record.args = (*args[:2], args[2].split("?", 1)[0] + "?...", *args[3:])
        return True


#: What a query parameter's name says when it carries a credential, compared without case, ``_``, ``-`` or ``.``
#: (``apiKey``, ``API-KEY``, ``x_auth_token``): anywhere in the name, or the whole name.
_CREDENTIAL_WORDS = (*(re.sub(r"[^a-z]", "", p) for p in TOKEN_PARAMETERS),
                     "auth", "secret", "password", "passwd", "credential", "session", "jwt")
_CREDENTIAL_NAMES = ("key", "pass", "pwd", "sig", "signature")


def credential_parameter(name: str, value: str) -> bool:
    """Whether a query parameter looks like it carries a token: by its name, or a value that is one of ours."""
    word = re.sub(r"[^a-z]", "", name.lower())
    return (value.startswith(TOKEN_PREFIX) or word in _CREDENTIAL_NAMES
            or any(part in word for part in _CREDENTIAL_WORDS))


def _refusal(request: Request, status: int, message: str):
    """A refusal as JSON on the API, as a page elsewhere."""
    if request.url.path.startswith("/api/") or request.url.path == "/health":
        return JSONResponse({"detail": message}, status_code=status)
    return web.forbidden(request, message) if status == 403 else JSONResponse({"detail": message}, status_code=status)


def allowed_methods(app: FastAPI, scope) -> list[str]:
    """Every method some route of ``app`` answers on the path of ``scope`` (the ``Allow`` header of a 405)."""
    def leaves(routes):
        for route in routes:
            # an included router (the service's are included without a prefix), or a mount
            inner = getattr(getattr(route, "original_router", route), "routes", None)
            yield from leaves(inner) if inner else (route,)

    methods = set()
    for route in leaves(app.routes):
        match, _ = route.matches(scope)
        if match != Match.NONE:
            methods |= set(getattr(route, "methods", None) or ())
    return sorted(methods)


def create_app(settings: Settings) -> FastAPI:
    """The application serving data directory ``settings.data``."""
    registry = Registry(settings.data)
    executor = Executor(registry, workers=settings.workers, scheduler=settings.scheduler)

    @asynccontextmanager
    async def lifespan(app: FastAPI):
        remove_staging_leftovers(settings.data)
        access = logging.getLogger("uvicorn.access")  # configured by uvicorn by now
        if not any(isinstance(f, WithoutQueryString) for f in access.filters):
            access.addFilter(WithoutQueryString())
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

    app.add_exception_handler(web.FormRefused, web.form_refused)

    @app.exception_handler(StarletteHTTPException)
    async def http_error(request: Request, exc: StarletteHTTPException):
        if exc.status_code == 405:  # Starlette names the methods of one route only; a path may have several
            exc.headers = {**(exc.headers or {}), "Allow": ", ".join(allowed_methods(app, request.scope))}
        return await http_exception_handler(request, exc)

    @app.middleware("http")
    async def security_headers(request: Request, call_next):
        in_url = sorted({k for k, v in request.query_params.multi_items() if credential_parameter(k, v)})
        if in_url:
            return _refusal(request, 400, f"a token is never accepted in a URL (query parameter {in_url[0]!r}): "
                                          "URLs end up in logs and browser histories; send it in the header "
                                          "'Authorization: Bearer <token>'")
        if request.method in UNSAFE_METHODS and "authorization" not in request.headers:
            cookie = COOKIE_NAME in request.cookies
            # a cookie request must come from this site's pages (CSRF); a login from another site is refused too
            why = cross_site(request.headers, strict=cookie) if cookie or request.url.path == "/login" else None
            if why:
                return _refusal(request, 403, f"cross-site request refused ({why}): a browser's sign-in acts only "
                                              "from this site's own pages; scripts send 'Authorization: Bearer'")
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
