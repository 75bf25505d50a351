"""The web page: server-rendered HTML (Jinja2) with a little JavaScript that polls the JSON API.

Pages: the campaign list (state, progress bar), the submit form (validation errors beside the spec),
a campaign page (verdict statements of the analysis with the report's page-1 figure of each fault sweep, live
progress, failures, links to the report and the data files), and the login form. A browser signs in by pasting a
token into the login form; the server answers with an HttpOnly, SameSite=Strict cookie holding it (see
:mod:`app.service.auth`).
"""

from __future__ import annotations

from datetime import UTC, datetime
from pathlib import Path
from urllib.parse import parse_qs

import jinja2
from fastapi import APIRouter, HTTPException, Request
from fastapi.concurrency import run_in_threadpool
from fastapi.responses import HTMLResponse, RedirectResponse
from fastapi.templating import Jinja2Templates

from app.service.api import (
    PayloadTooLarge,
    QueueFull,
    builtin_spec_texts,
    caller,
    campaign_files,
    cancel_campaign_as,
    describe,
    error_list,
    figures,
    read_limited,
    submit,
)
from app.service.auth import COOKIE_NAME, AuthError, identify
from app.service.registry import FINAL_STATES
from campaigns.runner.spec import SpecError

router = APIRouter(include_in_schema=False)
# every template autoescaped, whatever its file name (Starlette's default escapes only *.html, not *.html.j2):
# a campaign name, a spec, an error message are the user's text and never markup
templates = Jinja2Templates(env=jinja2.Environment(loader=jinja2.FileSystemLoader(Path(__file__).parent / "templates"),
                                                   autoescape=True))
#: Lifetime of the login cookie [s].
COOKIE_AGE = 12 * 3600
#: Most fields a form may post: the pages' forms have 3 at most (spec, runs, seed; token, next).
MAX_FORM_FIELDS = 20


class FormRefused(Exception):
    """A form body refused before it is read as one (413): too large, or too many fields."""


def _page(request: Request, name: str, status: int = 200, **context) -> HTMLResponse:
    return templates.TemplateResponse(request, name, {"who": context.pop("who", None), **context}, status_code=status)


def forbidden(request: Request, message: str) -> HTMLResponse:
    return _page(request, "message.html.j2", 403, title="Not allowed", message=message)


async def _form(request: Request) -> dict[str, str]:
    """The fields of a posted form (the first value of each); raises :class:`FormRefused`."""
    try:
        body = await read_limited(request)
    except PayloadTooLarge:
        raise FormRefused(f"The form is larger than the limit of {request.app.state.settings.max_spec_bytes} "
                          "bytes.") from None
    try:
        fields = parse_qs(body.decode("utf-8", errors="replace"), keep_blank_values=True,
                          max_num_fields=MAX_FORM_FIELDS)
    except ValueError:  # more fields than max_num_fields
        raise FormRefused(f"The form has more than {MAX_FORM_FIELDS} fields; this site's forms have 3 at most.") \
            from None
    return {k: v[0] for k, v in fields.items()}


def form_refused(request: Request, exc: FormRefused) -> HTMLResponse:
    """The page of a refused form (the application's handler of :class:`FormRefused`)."""
    return _page(request, "message.html.j2", 413, title="Form refused", message=str(exc))


def _now() -> float:
    return datetime.now(UTC).timestamp()


@router.get("/login", response_class=HTMLResponse)
def login_page(request: Request, next: str = "/"):
    return _page(request, "login.html.j2", next=_local(next), error="")


@router.post("/login")
async def login(request: Request):
    form = await _form(request)
    target = _local(form.get("next", "/"))
    try:
        await run_in_threadpool(identify, request.app.state.registry, None, form.get("token", "").strip())
    except AuthError as exc:
        return _page(request, "login.html.j2", 401, next=target, error=str(exc))
    response = RedirectResponse(target, status_code=303)
    response.set_cookie(COOKIE_NAME, form["token"].strip(), max_age=COOKIE_AGE, httponly=True, samesite="strict",
                        secure=request.url.scheme == "https")
    return response


@router.post("/logout")
def logout(request: Request):
    response = RedirectResponse("/login", status_code=303)
    response.delete_cookie(COOKIE_NAME)
    return response


def _local(target: str) -> str:
    """Only a path of this site (no open redirect)."""
    return target if target.startswith("/") and not target.startswith("//") else "/"


@router.get("/", response_class=HTMLResponse)
def index(request: Request):
    who = caller(request)
    registry = request.app.state.registry
    rows = [describe(registry, r, _now()) for r in registry.campaigns()]
    return _page(request, "index.html.j2", who=who, campaigns=rows)


@router.get("/submit", response_class=HTMLResponse)
def submit_page(request: Request, example: str = "demo.toml"):
    who = caller(request, "submit")
    examples = builtin_spec_texts()
    text = examples.get(example, "")
    return _page(request, "submit.html.j2", who=who, examples=sorted(examples), example=example, spec=text,
                 runs="", seed="", errors=[], detail="")


@router.post("/submit", response_class=HTMLResponse)
async def submit_form(request: Request):
    who = await run_in_threadpool(caller, request, "submit")
    examples = sorted(builtin_spec_texts())
    form = await _form(request)
    text, runs, seed = form.get("spec", ""), form.get("runs", "").strip(), form.get("seed", "").strip()
    context = {"who": who, "examples": examples, "example": "", "spec": text, "runs": runs, "seed": seed}
    numbers, problems = {}, []
    for key in ("runs", "seed"):
        if context[key]:
            try:
                numbers[key] = int(context[key])
            except ValueError:
                problems.append(f"{key}: must be a whole number, got {context[key]!r}")
    try:
        if problems:
            raise SpecError(problems)
        record = await run_in_threadpool(submit, request, text, numbers.get("runs"), numbers.get("seed"), who)
    except SpecError as exc:
        return _page(request, "submit.html.j2", 422, errors=error_list(exc.problems),
                     detail=f"{len(exc.problems)} problem(s)", **context)
    except QueueFull as exc:  # the spec stays in the form, to submit once a place is free
        return _page(request, "submit.html.j2", 429, errors=error_list([str(exc)]), detail="queue limit reached",
                     **context)
    return RedirectResponse(f"/campaigns/{record['id']}", status_code=303)


@router.get("/campaigns/{campaign_id}", response_class=HTMLResponse)
def campaign_page(request: Request, campaign_id: str):
    who = caller(request)
    registry = request.app.state.registry
    record = registry.campaign(campaign_id)
    if record is None:
        return _page(request, "message.html.j2", 404, who=who, title="No such campaign",
                     message=f"There is no campaign {campaign_id!r}.")
    campaign = describe(registry, record, _now())
    owner = who["role"] == "admin" or record["submitted_by"] == who["name"]
    can_cancel = record["state"] not in FINAL_STATES and owner
    return _page(request, "campaign.html.j2", who=who, c=campaign, can_cancel=can_cancel,
                 file_names=list(campaign_files(record)), figures=figures(record))


@router.post("/campaigns/{campaign_id}/cancel")
async def cancel_form(request: Request, campaign_id: str):
    who = await run_in_threadpool(caller, request, "submit")
    try:
        await run_in_threadpool(cancel_campaign_as, request, campaign_id, who)
    except HTTPException as exc:
        return _page(request, "message.html.j2", exc.status_code, who=who, title="Cannot cancel", message=exc.detail)
    return RedirectResponse(f"/campaigns/{campaign_id}", status_code=303)
