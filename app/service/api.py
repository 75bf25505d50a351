"""The JSON API, ``/api/v1`` (OpenAPI schema at ``/api/v1/openapi.json``), and ``/health``."""

from __future__ import annotations

import os
import re
import shutil
import stat
from datetime import UTC, datetime
from pathlib import Path

from fastapi import APIRouter, HTTPException, Query, Request
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import FileResponse, JSONResponse
from pydantic import BaseModel

import campaigns
from app.service.auth import COOKIE_NAME, identify, require
from app.service.registry import FINAL_STATES
from app.service.submission import ANSWER_FIGURE_NAME, SUBMITTED_NAME, input_dir, output_dir, prepare
from campaigns.runner.budget import estimate
from campaigns.runner.spec import SpecError

router = APIRouter()

#: The files every campaign may have: name -> (where, file name, media type). With the page-1 figures its summary lists
#: (:func:`campaign_files`), nothing else is served.
FILES = {
    "results.nc": ("out", "results.nc", "application/x-netcdf"),
    "analysis.nc": ("out", "analysis.nc", "application/x-netcdf"),
    "report.html": ("out", "report.html", "text/html; charset=utf-8"),
    "report.pdf": ("out", "report.pdf", "application/pdf"),
    "spec": ("input", SUBMITTED_NAME, "text/plain; charset=utf-8"),
    "spec.json": ("out", "spec.json", "application/json"),
}
#: Files shown in the browser rather than downloaded (the page-1 figures too).
INLINE = ("report.html", "report.pdf", "spec", "spec.json")
#: The generated report is shown as it is: its own CSS and embedded figures, no scripts, no external loads.
REPORT_POLICY = "default-src 'none'; style-src 'unsafe-inline'; img-src data:; frame-ancestors 'none'"
_PATH = re.compile(r"^[A-Za-z_][\w.\[\]]*$")

#: The answers every route documents in the OpenAPI schema besides its own (``responses=`` of each route).
_ERROR = {"content": {"application/json": {"schema": {"type": "object", "properties": {"detail": {"type": "string"}}}}}}
AUTHENTICATED = {
    400: {"description": "a token in the URL (?token=...): refused, tokens travel in the Authorization header",
          **_ERROR},
    401: {"description": "no token, or an unknown or revoked one", **_ERROR},
    403: {"description": "a token with too small a role, or a cookie-authenticated change from another site",
          **_ERROR},
}
NOT_FOUND = {404: {"description": "no such campaign", **_ERROR}}


class PayloadTooLarge(Exception):
    pass


class QueueFull(Exception):
    """The submitter has the service's limit of campaigns queued or running already (429): its message says
    the limit and how many there are."""

    def __init__(self, who: str, limit: int, active: dict[str, int]):
        super().__init__(
            f"{who!r} has {sum(active.values())} campaign(s) queued or running ({active['queued']} queued, "
            f"{active['running']} running); this service takes at most {limit} per user (twin serve "
            "--max-queued-per-user): nothing was queued; cancel one or wait until one finishes")


class SpecSubmission(BaseModel):
    """A spec as JSON (the alternative to a raw TOML body)."""

    spec: str
    runs: int | None = None
    seed: int | None = None


def caller(request: Request, role: str = "read") -> dict:
    """The token record of a request with at least ``role`` (401/403 otherwise)."""
    registry = request.app.state.registry
    record = identify(registry, request.headers.get("authorization"), request.cookies.get(COOKIE_NAME))
    require(record, role)
    return record


async def read_limited(request: Request) -> bytes:
    """The request body, refused (413) beyond the configured size before it is all read."""
    limit = request.app.state.settings.max_spec_bytes
    declared = request.headers.get("content-length")
    if declared is not None and declared.isdigit() and int(declared) > limit:
        raise PayloadTooLarge
    body = bytearray()
    async for part in request.stream():
        body += part
        if len(body) > limit:
            raise PayloadTooLarge
    return bytes(body)


def too_large(request: Request) -> JSONResponse:
    limit = request.app.state.settings.max_spec_bytes
    return JSONResponse({"detail": f"the spec is larger than the limit of {limit} bytes"}, status_code=413)


def error_list(problems: list[str]) -> list[dict]:
    """``"path: message"`` problems as ``{"path", "message"}`` (``path`` empty when a problem names none)."""
    errors = []
    for problem in problems:
        path, sep, message = problem.partition(": ")
        named = sep and _PATH.match(path)
        errors.append({"path": path, "message": message} if named else {"path": "", "message": problem})
    return errors


def cost_problems(spec, settings) -> list[str]:
    """The campaign's estimated duration against the service's limit (``twin serve --max-campaign-hours``): one
    problem saying why when it is beyond it, before anything is queued."""
    from campaigns.bench.adapter import simulate_run  # lazy: the twin's catalog loads with the first submission

    cost = estimate(spec, simulate_run, workers=settings.workers)
    limit = settings.max_campaign_hours * 3600.0
    if cost.wall_seconds is None or cost.wall_seconds <= limit:
        return []
    return [f"runs_per_dataset: the campaign would take {cost.describe()} (about {cost.run_seconds:.2g} s per run), "
            f"beyond this service's limit of {settings.max_campaign_hours:g} h per campaign (twin serve "
            "--max-campaign-hours); submit fewer runs (?runs=N) or split it into several campaigns"]


def submit(request: Request, text: str, runs: int | None, seed: int | None, who: dict) -> dict:
    """Validate, estimate and queue a spec (blocking: call it in a worker thread); the campaign's record.

    Raises :class:`SpecError` or :class:`QueueFull`, and then nothing is queued.
    """
    registry = request.app.state.registry
    settings = request.app.state.settings
    limit = settings.max_queued_per_user
    active = registry.active_of(who["name"])
    if sum(active.values()) >= limit:  # before any work; the insert below counts again, atomically
        raise QueueFull(who["name"], limit, active)
    submission = prepare(registry.data, text, runs=runs, seed=seed, check=lambda spec: cost_problems(spec, settings))
    spec = submission.spec
    if not registry.add_campaign(submission.campaign_id, spec.name, spec.spec_hash(),
                                 len(spec.datasets) * spec.runs_per_dataset, submission.overrides, who["name"],
                                 max_active=limit):  # a concurrent submission took the last place
        shutil.rmtree(registry.campaign_dir(submission.campaign_id), ignore_errors=True)
        raise QueueFull(who["name"], limit, registry.active_of(who["name"]))
    request.app.state.executor.notify()
    return registry.campaign(submission.campaign_id)


def _iso(t: float | None) -> str | None:
    return datetime.fromtimestamp(t, UTC).isoformat(timespec="seconds") if t else None


def figures(record: dict) -> list[dict[str, str]]:
    """The page-1 figures a finished campaign's summary lists (``{"name", "caption"}``, one per fault sweep, as the
    runner drew them: :func:`app.service.runner.answer_figures`), those of a figure's name alone."""
    listed = (record["summary"] or {}).get("figures", [])
    return [f for f in listed if ANSWER_FIGURE_NAME.match(f["name"])]


def campaign_files(record: dict) -> dict[str, tuple[str, str, str]]:
    """The files of a campaign that may be downloaded, as :data:`FILES`: those and the page-1 figures its summary
    lists. Nothing else is served."""
    return {**FILES, **{f["name"]: ("out", f["name"], "image/png") for f in figures(record)}}


def available_files(registry, record: dict) -> list[str]:
    return [name for name in campaign_files(record) if served_file(registry, record, name) is not None]


def _file(campaign_dir: Path, where: str, file: str) -> Path:
    return (output_dir(campaign_dir) if where == "out" else input_dir(campaign_dir)) / file


def served_file(registry, record: dict, name: str) -> Path | None:
    """The file ``name`` of a campaign (one of :func:`campaign_files`) if it may be served: a regular file at its own
    place inside the campaign's directory, reached through no symbolic link (one planted in the output cannot lead
    outside); else None."""
    where, file, _ = campaign_files(record)[name]
    path = _file(registry.campaign_dir(record["id"]), where, file)
    try:
        real = path.resolve(strict=True)
        expected = registry.data.resolve(strict=True) / path.relative_to(registry.data)
        return real if real == expected and stat.S_ISREG(os.lstat(real).st_mode) else None
    except (OSError, RuntimeError, ValueError):  # missing, a symlink loop, outside the data directory
        return None


def describe(registry, record: dict, now: float) -> dict:
    """The public view of a campaign record."""
    started, finished = record["started_at"], record["finished_at"]
    total, done = record["runs_total"], record["runs_done"]
    campaign_id = record["id"]
    return {
        "id": campaign_id,
        "name": record["name"],
        "state": record["state"],
        "stage": record["stage"],
        "stage_message": record["stage_message"],
        "spec_hash": record["spec_hash"],
        "overrides": record["overrides"],
        "submitted_by": record["submitted_by"],
        "progress": {"runs_done": done, "runs_total": total,
                     "percent": round(100.0 * done / total, 1) if total else 0.0,
                     "failures": record["failures"], "failure_examples": record["failure_examples"]},
        "timings": {
            "submitted_at": _iso(record["submitted_at"]),
            "started_at": _iso(started),
            "finished_at": _iso(finished),
            "queued_seconds": round((started or now) - record["submitted_at"], 1),
            "running_seconds": round((finished or now) - started, 1) if started else None,
        },
        "legs": record["legs"],
        "cancel_requested": bool(record["cancel_requested"]),
        "error": record["error"],
        "summary": record["summary"] or {},
        "files": {name: f"/api/v1/campaigns/{campaign_id}/files/{name}"
                  for name in available_files(registry, record)},
        "page": f"/campaigns/{campaign_id}",
    }


@router.get("/health", tags=["service"], responses={400: AUTHENTICATED[400]})
def health(request: Request) -> dict:
    """Liveness (no token): the service answers and its registry is readable."""
    registry = request.app.state.registry
    return {"status": "ok", "queued": len(registry.ids_in_state("queued")),
            "running": len(registry.ids_in_state("running"))}


@router.get("/api/v1/campaigns", tags=["campaigns"], responses=AUTHENTICATED)
def list_campaigns(request: Request, limit: int = Query(200, ge=1, le=1000)) -> dict:
    """The latest campaigns, newest first (role ``read``)."""
    caller(request)
    registry, now = request.app.state.registry, datetime.now(UTC).timestamp()
    return {"campaigns": [describe(registry, r, now) for r in registry.campaigns(limit)]}


@router.post("/api/v1/campaigns", status_code=201, tags=["campaigns"],
             openapi_extra={"requestBody": {"required": True, "content": {
                 "application/toml": {"schema": {"type": "string"}},
                 "application/json": {"schema": SpecSubmission.model_json_schema()}}}},
             responses={**AUTHENTICATED,
                        413: {"description": "spec larger than the limit", **_ERROR},
                        422: {"description": "every validation problem with its field path (the estimated duration "
                                             "beyond the service's limit too); nothing queued"},
                        429: {"description": "the submitter has the service's limit of campaigns queued or running "
                                             "already (twin serve --max-queued-per-user); nothing queued", **_ERROR}})
async def create_campaign(request: Request, runs: int | None = Query(None, description="runs per data set (override)"),
                          seed: int | None = Query(None, description="root seed (override)")):
    """Submit a spec (role ``submit``): a TOML body, or JSON ``{"spec", "runs", "seed"}``."""
    who = await run_in_threadpool(caller, request, "submit")
    try:
        body = await read_limited(request)
    except PayloadTooLarge:
        return too_large(request)
    try:
        if request.headers.get("content-type", "").startswith("application/json"):
            payload = SpecSubmission.model_validate_json(body)
            text, runs, seed = payload.spec, payload.runs if payload.runs is not None else runs, \
                payload.seed if payload.seed is not None else seed
        else:
            text = body.decode("utf-8")
    except (ValueError, UnicodeDecodeError) as exc:
        return JSONResponse({"detail": "unreadable request body", "errors": [{"path": "", "message": str(exc)}]},
                            status_code=422)
    try:
        record = await run_in_threadpool(submit, request, text, runs, seed, who)
    except SpecError as exc:
        return JSONResponse({"detail": f"invalid campaign spec ({len(exc.problems)} problem(s)); nothing was queued",
                             "errors": error_list(exc.problems)}, status_code=422)
    except QueueFull as exc:
        return JSONResponse({"detail": str(exc)}, status_code=429)
    now = datetime.now(UTC).timestamp()
    return JSONResponse(describe(request.app.state.registry, record, now), status_code=201,
                        headers={"Location": f"/api/v1/campaigns/{record['id']}"})


def _record(request: Request, campaign_id: str) -> dict:
    record = request.app.state.registry.campaign(campaign_id)
    if record is None:
        raise HTTPException(404, f"no campaign {campaign_id!r}")
    return record


@router.get("/api/v1/campaigns/{campaign_id}", tags=["campaigns"], responses={**AUTHENTICATED, **NOT_FOUND})
def get_campaign(request: Request, campaign_id: str) -> dict:
    """State, progress, failures, timings, spec hash, verdict statements (role ``read``)."""
    caller(request)
    return describe(request.app.state.registry, _record(request, campaign_id), datetime.now(UTC).timestamp())


def cancel_campaign_as(request: Request, campaign_id: str, who: dict) -> dict:
    """Cancel as ``who`` (submitter of the campaign, or admin); the campaign's view afterwards."""
    record = _record(request, campaign_id)
    if who["role"] != "admin" and record["submitted_by"] != who["name"]:
        raise HTTPException(403, f"campaign {campaign_id} was submitted by {record['submitted_by']!r}; "
                                 "only its submitter or an admin may cancel it")
    if record["state"] in FINAL_STATES:
        raise HTTPException(409, f"campaign {campaign_id} is {record['state']} already")
    request.app.state.executor.cancel(campaign_id)
    return describe(request.app.state.registry, _record(request, campaign_id), datetime.now(UTC).timestamp())


@router.post("/api/v1/campaigns/{campaign_id}/cancel", tags=["campaigns"],
             responses={**AUTHENTICATED, **NOT_FOUND, 409: {"description": "the campaign is finished already",
                                                            **_ERROR}})
def cancel_campaign(request: Request, campaign_id: str) -> dict:
    """Cancel a queued or running campaign (role ``submit`` for one's own, ``admin`` for any); 409 if finished."""
    return cancel_campaign_as(request, campaign_id, caller(request, "submit"))


@router.get("/api/v1/campaigns/{campaign_id}/files/{name}", tags=["campaigns"],
            responses={**AUTHENTICATED, 404: {"description": "unknown campaign, a name not in the list, not written "
                                                             "yet, or not a regular file of the campaign", **_ERROR}})
def get_file(request: Request, campaign_id: str, name: str):
    """One of ``results.nc``, ``analysis.nc``, ``report.html``, ``report.pdf``, ``spec`` (as submitted),
    ``spec.json`` (canonical), and the report's page-1 figure of each fault sweep the campaign's summary lists
    (``detection.png``, ``detection_preload.png``) (role ``read``). Any other name is 404."""
    caller(request)
    record = _record(request, campaign_id)
    files = campaign_files(record)
    if name not in files:
        raise HTTPException(404, f"no file {name!r}; available names: {', '.join(files)}")
    media = files[name][2]
    path = served_file(request.app.state.registry, record, name)
    if path is None:
        raise HTTPException(404, f"{name} of campaign {campaign_id} does not exist (yet)")
    download = name if name != "spec" else f"{record['name']}.toml"
    headers = {"Content-Security-Policy": REPORT_POLICY} if name == "report.html" else {}
    inline = name in INLINE or name not in FILES
    return FileResponse(path, media_type=media, filename=download, headers=headers,
                        content_disposition_type="inline" if inline else "attachment")


def builtin_spec_texts() -> dict[str, str]:
    """The built-in specs by file name (the submit form's examples)."""
    specs = Path(campaigns.__file__).parent / "specs"
    return {p.name: p.read_text(encoding="utf-8") for p in sorted(specs.glob("*.toml"))}
