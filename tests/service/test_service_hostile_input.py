"""Issue 39's probes of the service, in this process (nothing runs): a deeply nested spec, a form with too many
fields, a credential in any query parameter, a user filling the queue. Each gets one clear answer, never a 5xx,
and nothing is queued by a refused request."""

from __future__ import annotations

import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from urllib.parse import urlencode

import pytest
from service_helpers import SPEC, LocalService

from app.service.submission import MAX_NESTING

FORM = {"content-type": "application/x-www-form-urlencoded", "sec-fetch-site": "same-origin"}


@pytest.fixture
def local(tmp_path):
    return LocalService(tmp_path / "data")


def _nested_arrays(depth: int) -> str:
    return "a = " + "[" * depth + "]" * depth


TOO_DEEP = f"tables and arrays nested more than {MAX_NESTING} levels deep (the built-in specs nest 4)"
TOO_MANY_PARTS = f"a dotted key or table name of more than {MAX_NESTING} parts"
NESTED = {  # the probe, what it is refused with
    "100000 open arrays (the probe)": ("a = " + "[" * 100_000, TOO_DEEP),
    "1000 inline tables": ("a = " + "{b = " * 1000 + "1" + "}" * 1000, TOO_DEEP),
    f"{MAX_NESTING + 1} levels, one beyond the bound": (_nested_arrays(MAX_NESTING), TOO_DEEP),
    "header, key and value each within the bound": ("[" + ".".join("t" * 8) + "]\n" + ".".join("k" * 8) + " = [[1]]",
                                                    TOO_DEEP),
    # tomllib builds a dotted key part by part, in quadratic time: refused by the count of its parts, unparsed
    "10000 dotted keys": ("# a comment\na" + ".a" * 10_000 + " = 1", f"line 2: {TOO_MANY_PARTS}"),
    "a 10000-part table header": ("# a comment\n[t" + ".t" * 10_000 + "]\nx = 1", f"line 2: {TOO_MANY_PARTS}"),
    "quoted parts": ("# a comment\nx = 1\n" + '"q".' * MAX_NESTING + "z = 1", f"line 3: {TOO_MANY_PARTS}"),
}
#: Brackets, dots and quotes in strings and comments, as the parser reads them: no nesting, no key parts.
HARMLESS = r'''name = "[[[[[[[[[[[[[[[[[[[[ \" a.b.c.d.e.f.g.h.i.j.k.l.m.n.o.p.q.r"
description = """[[[[[[[[[[[[[[[[[[[ \""" {{{{{{{{{{{{{{{{{{{{
[[[[[[[[[[[[[[[[[[[[["""
extends = '[[[[[[[[[[[[[[[[[[[[[['  # [[[[[[[[[[[[[[[[[[[[[[[[ a.b.c.d.e.f.g.h.i.j.k.l.m.n.o.p.q.r
"a.b.c.d.e.f.g.h.i.j.k.l.m.n.o.p.q.r" = 1
'''


@pytest.mark.parametrize("text, message", NESTED.values(), ids=NESTED.keys())
def test_a_deeply_nested_spec_is_one_422_line_and_nothing_is_queued(local, text, message):
    api = local.client("alice")
    for response in (api.post("/api/v1/campaigns", content=text), api.post("/api/v1/campaigns", json={"spec": text})):
        assert response.status_code == 422, response.text
        assert response.json()["errors"] == [{"path": "spec", "message": message}]
    form = urlencode({"spec": text})
    page = api.post("/submit", content=form, headers=FORM)
    if len(form) > local.app.state.settings.max_spec_bytes:  # the probe's 100000 brackets, 3 bytes each in a form
        assert page.status_code == 413 and "The form is larger than the limit" in page.text
    else:
        assert page.status_code == 422 and message in page.text
    assert local.campaign_ids() == [] and not list((local.registry.data / "staging").glob("*"))


def test_brackets_and_dots_in_strings_and_comments_are_no_nesting(local):
    response = local.client("alice").post("/api/v1/campaigns", content=HARMLESS)
    assert response.status_code == 422
    errors = response.json()["errors"]
    assert [e["path"] for e in errors] == ["extends"], errors  # read as TOML: its extends is its problem


def test_nesting_within_the_bound_goes_on_to_the_validation(local):
    response = local.client("alice").post("/api/v1/campaigns", content=_nested_arrays(MAX_NESTING - 1))
    assert response.status_code == 422
    assert not any("nested" in e["message"] for e in response.json()["errors"])  # the spec's own problems


def test_an_integer_beyond_pythons_digit_limit_is_one_422_line(local):
    response = local.client("alice").post("/api/v1/campaigns", content="runs_per_dataset = " + "1" * 5000)
    assert response.status_code == 422, response.text
    [error] = response.json()["errors"]
    assert error["path"] == "spec" and error["message"].startswith("not readable (Exceeds the limit (4300 digits)")
    assert "sys.set_int_max_str_digits" not in error["message"]  # advice for a programmer, not for the submitter


@pytest.mark.parametrize("path", ["/submit", "/login"])
def test_a_form_with_too_many_fields_or_bytes_is_413_with_a_message(local, path):
    browser = local.client("alice")
    many = "&".join(f"f{k}=1" for k in range(21))
    response = browser.post(path, content=many, headers=FORM)
    assert response.status_code == 413, response.text
    assert "The form has more than 20 fields; this site&#39;s forms have 3 at most." in response.text
    large = "spec=" + "x" * (local.app.state.settings.max_spec_bytes + 1)
    response = browser.post(path, content=large, headers=FORM)
    assert response.status_code == 413 and "The form is larger than the limit of 262144 bytes." in response.text
    twenty = "&".join(f"f{k}=1" for k in range(20))  # at the bound: read as a form (a spec or token missing)
    assert browser.post(path, content=twenty, headers=FORM).status_code in (401, 422)
    assert local.campaign_ids() == []


@pytest.mark.parametrize("name", ["token", "Token", "access_token", "apikey", "apiKey", "API-KEY", "api_key",
                                  "x-api-key", "key", "auth", "Authorization", "bearer", "id_token", "sessionid",
                                  "password", "client_secret", "jwt", "sig"])
def test_a_credential_in_any_query_parameter_is_refused(local, name):
    token = local.client("reader", "read").headers["authorization"].split()[1]
    anonymous = local.client()
    for path in ("/api/v1/campaigns", "/health", "/"):
        response = anonymous.get(path, params={name: token})
        assert response.status_code == 400, (path, response.text)
        assert f"never accepted in a URL (query parameter {name!r})" in response.json()["detail"]
        assert token not in response.text


def test_a_token_of_ours_under_any_name_is_refused_and_plain_parameters_pass(local):
    reader = local.client("reader", "read")
    token = reader.headers["authorization"].split()[1]
    response = reader.get("/api/v1/campaigns", params={"q": token})
    assert response.status_code == 400 and "'q'" in response.json()["detail"]
    assert reader.get("/api/v1/campaigns", params={"limit": 3}).status_code == 200
    assert reader.get("/submit", params={"example": "demo.toml"}).status_code == 403  # the role, not the URL
    assert reader.get("/login", params={"next": "/campaigns/x"}).status_code == 200


def _submit(api, runs: int = 1):
    return api.post("/api/v1/campaigns", content=SPEC.read_text(), params={"runs": runs})


def test_each_user_may_have_a_few_campaigns_waiting_and_429_says_how_many(tmp_path):
    local = LocalService(tmp_path / "data", max_queued_per_user=2)
    alice, bob, admin = local.client("alice"), local.client("bob"), local.client("root", "admin")
    accepted = [_submit(alice).json()["id"] for _ in range(2)]
    local.registry.update(accepted[0], state="running")
    response = _submit(alice)
    assert response.status_code == 429
    assert response.json()["detail"] == (
        "'alice' has 2 campaign(s) queued or running (1 queued, 1 running); this service takes at most 2 per user "
        "(twin serve --max-queued-per-user): nothing was queued; cancel one or wait until one finishes")
    page = alice.post("/submit", data={"spec": SPEC.read_text()}, headers=FORM)
    assert page.status_code == 429 and "takes at most 2 per user" in page.text
    assert "name = &#34;service_small_thesis&#34;" in page.text  # the spec stays in the form (escaped)
    assert _submit(bob).status_code == 201  # the limit is each user's own
    assert [_submit(admin).status_code for _ in range(3)] == [201, 201, 429]  # an admin's script is a script too
    assert local.campaign_ids()[::-1][:2] == accepted and len(local.campaign_ids()) == 5
    assert alice.post(f"/api/v1/campaigns/{accepted[1]}/cancel").json()["state"] == "cancelled"
    local.registry.update(accepted[0], state="done")
    assert [_submit(alice).status_code for _ in range(3)] == [201, 201, 429]  # finished ones hold no place


def test_concurrent_submissions_cannot_all_pass_the_count(tmp_path):
    local = LocalService(tmp_path / "data", max_queued_per_user=3)
    alice = local.client("alice")
    with ThreadPoolExecutor(8) as pool:
        codes = sorted(pool.map(lambda _: _submit(alice).status_code, range(8)))
    assert codes == [201] * 3 + [429] * 5  # whatever the interleaving: the count and the insert are one statement
    on_disk = sorted(p.name for p in (local.registry.data / "campaigns").iterdir())
    assert on_disk == sorted(local.campaign_ids())  # a submission refused at the insert left no inputs behind


def test_the_limit_is_a_twin_serve_option_checked_before_serving(tmp_path):
    result = subprocess.run([sys.executable, "-m", "app.cli", "serve", "--data", str(tmp_path),
                             "--max-queued-per-user", "0"], capture_output=True, text=True, timeout=600)
    assert result.returncode != 0
    assert result.stderr.strip().splitlines() == ["twin serve: error: --max-queued-per-user must be >= 1, got 0"]
