"""Issue 31, rows 3, 4, 5 and 8 against a real server: stored markup is escaped, a cookie acts only from the
service's own pages, the files endpoint serves only the campaign's own regular files, a token in a URL is
refused and never logged, the schema documents every answer, a campaign beyond the service's limit is refused
before it is queued."""

from __future__ import annotations

import httpx
import pytest
from service_helpers import SPEC, client, wait_final

from app.service.auth import COOKIE_NAME

MARKUP = '<b id="injected">x</b><a href="https://evil.example">link</a>'


def _cookie_client(service, role: str = "submitter", **headers) -> httpx.Client:
    """A browser-like client: the login cookie, no Authorization header."""
    return httpx.Client(base_url=service.url, cookies={COOKIE_NAME: service.tokens[role]}, headers=headers,
                        timeout=120, follow_redirects=False)


def _queued_and_cancelled(service, text: str) -> dict:
    """Submit ``text`` (bearer token), cancel it at once (nothing runs): its record."""
    submitter = client(service, service.tokens["submitter"])
    response = submitter.post("/api/v1/campaigns", content=text, params={"runs": 1})
    assert response.status_code == 201, response.text
    campaign_id = response.json()["id"]
    client(service, service.tokens["admin"]).post(f"/api/v1/campaigns/{campaign_id}/cancel")
    return wait_final(submitter, campaign_id)


def test_markup_in_user_fields_is_escaped_on_every_page(service):
    """A campaign name is letters, digits, _ and - (issue 39: it names out/<name>), so markup never becomes a
    campaign's name: refused before anything is queued, and the refusal shows it back escaped."""
    text = SPEC.read_text().replace('name = "service_small_thesis"', f"name = '{MARKUP}'")
    submitter = client(service, service.tokens["submitter"])
    before = submitter.get("/api/v1/campaigns").json()["campaigns"]
    response = submitter.post("/api/v1/campaigns", content=text, params={"runs": 1})
    assert response.status_code == 422 and response.json()["errors"][0]["path"] == "name", response.text
    assert submitter.get("/api/v1/campaigns").json()["campaigns"] == before  # nothing queued
    with _cookie_client(service) as browser:
        refused = browser.post("/submit", data={"spec": text, "runs": "1"}, headers={"Origin": service.url})
        assert refused.status_code == 422
        assert "&lt;b id=&#34;injected&#34;&gt;x&lt;/b&gt;" in refused.text
        assert "<b id=" not in refused.text and 'href="https://evil.example"' not in refused.text
        page = browser.get("/").text
        assert "<b id=" not in page and 'href="https://evil.example"' not in page
        # a spec's own text and its errors are shown back escaped too
        response = browser.post("/submit", data={"spec": f"name = 3\n# </textarea>{MARKUP}", "runs": "x<i>"},
                                headers={"Origin": service.url})
        assert response.status_code == 422
        assert "</textarea><b" not in response.text and "x<i>" not in response.text
        assert "&lt;/textarea&gt;&lt;b" in response.text and "x&lt;i&gt;" in response.text


def test_a_cookie_acts_only_from_the_services_own_pages(service):
    submitter = client(service, service.tokens["submitter"])
    before = submitter.get("/api/v1/campaigns").json()["campaigns"]
    spec = SPEC.read_text()
    refused = [
        {"Origin": "http://evil.example"},
        {"Origin": "null"},
        {"Sec-Fetch-Site": "cross-site", "Origin": service.url},
        {"Sec-Fetch-Site": "same-site"},
        {},  # a cookie and nothing that says where the request comes from: no browser sends that
    ]
    for headers in refused:
        with _cookie_client(service, **headers) as browser:
            response = browser.post("/api/v1/campaigns", content=spec, params={"runs": 1})
            assert response.status_code == 403 and "cross-site" in response.json()["detail"], (headers, response.text)
            assert browser.post("/submit", data={"spec": spec}).status_code == 403, headers
            assert browser.post("/logout").status_code == 403, headers
    assert submitter.get("/api/v1/campaigns").json()["campaigns"] == before  # nothing queued
    broken = "name = 3\n"  # same-origin requests get through to the validation (422: nothing queued either)
    for headers in ({"Origin": service.url}, {"Sec-Fetch-Site": "same-origin"}):
        with _cookie_client(service, **headers) as browser:
            assert browser.post("/api/v1/campaigns", content=broken).status_code == 422, headers
    # bearer clients are not concerned, whatever their headers say
    response = submitter.post("/api/v1/campaigns", content=broken, headers={"Origin": "http://evil.example"})
    assert response.status_code == 422
    # a login posted from another site is refused as well (login CSRF)
    anonymous = httpx.Client(base_url=service.url, timeout=60)
    response = anonymous.post("/login", data={"token": service.tokens["reader"]},
                              headers={"Origin": "http://evil.example"})
    assert response.status_code == 403 and COOKIE_NAME not in response.headers.get("set-cookie", "")
    anonymous.close()


def test_the_files_endpoint_serves_only_the_campaigns_own_regular_files(service, tmp_path):
    record = _queued_and_cancelled(service, SPEC.read_text())
    campaign_dir = service.data / "campaigns" / record["id"]
    out = campaign_dir / "out"
    out.mkdir(exist_ok=True)
    secret = tmp_path / "secret.txt"
    secret.write_text("outside the data directory")
    (out / "results.nc").symlink_to(secret)
    (out / "analysis.nc").symlink_to(service.data / "registry.sqlite3")
    (out / "report.html").symlink_to(campaign_dir / "input" / "submitted.toml")  # inside, but a link
    (out / "report.pdf").mkdir()  # not a regular file
    reader = client(service, service.tokens["reader"])
    for name in ("results.nc", "analysis.nc", "report.html", "report.pdf"):
        response = reader.get(f"/api/v1/campaigns/{record['id']}/files/{name}")
        assert response.status_code == 404, name
        assert b"outside the data directory" not in response.content and b"SQLite" not in response.content
    assert reader.get(f"/api/v1/campaigns/{record['id']}/files/spec").status_code == 200  # the real file
    listed = reader.get(f"/api/v1/campaigns/{record['id']}").json()["files"]
    assert sorted(listed) == ["spec"]


def test_a_token_in_a_url_is_refused_and_never_logged(service):
    token = service.tokens["reader"]
    anonymous = client(service, None)
    for name in ("token", "access_token", "Token", "apikey"):
        response = anonymous.get("/api/v1/campaigns", params={name: token})
        assert response.status_code == 400 and "never accepted in a URL" in response.json()["detail"]
    response = anonymous.get("/", params={"token": token})
    assert response.status_code == 400
    log = service.log()
    assert token not in log
    assert '"GET /api/v1/campaigns?... HTTP/1.1" 400' in log  # the request is logged, its query string is not


def test_the_schema_documents_every_answer_and_405_lists_every_method(service):
    schema = client(service, None).get("/api/v1/openapi.json").json()["paths"]
    expected = {
        ("/api/v1/campaigns", "get"): {"400", "401", "403", "422"},
        ("/api/v1/campaigns", "post"): {"201", "400", "401", "403", "413", "422", "429"},
        ("/api/v1/campaigns/{campaign_id}", "get"): {"401", "403", "404", "422"},
        ("/api/v1/campaigns/{campaign_id}/cancel", "post"): {"401", "403", "404", "409", "422"},
        ("/api/v1/campaigns/{campaign_id}/files/{name}", "get"): {"401", "403", "404", "422"},
    }
    for (path, method), codes in expected.items():
        documented = set(schema[path][method]["responses"])
        assert codes <= documented, (path, method, codes - documented)
    reader = client(service, service.tokens["reader"])
    for method, path, allowed in (("DELETE", "/api/v1/campaigns", {"GET", "POST"}),
                                  ("PUT", "/api/v1/campaigns/x/cancel", {"POST"}),
                                  ("POST", "/api/v1/campaigns/x/files/spec", {"GET"})):
        response = reader.request(method, path)
        assert response.status_code == 405
        assert {m.strip() for m in response.headers["allow"].split(",")} == allowed, (path, response.headers)


@pytest.mark.parametrize("setting, field", [("dt = 1e-7", "runs_per_dataset"), ("timeout = 1e12", "execution.timeout")])
def test_a_campaign_beyond_the_limits_is_refused_before_it_is_queued(service, setting, field):
    submitter = client(service, service.tokens["submitter"])
    before = submitter.get("/api/v1/campaigns").json()["campaigns"]
    table = "[solver]" if setting.startswith("dt") else "[execution]"
    text = SPEC.read_text().replace("[execution]", f"[execution]\n{setting}" if table == "[execution]"
                                    else f"[solver]\n{setting}\n\n[execution]")
    response = submitter.post("/api/v1/campaigns", content=text, params={"runs": 20000})
    assert response.status_code == 422, response.text
    errors = {e["path"]: e["message"] for e in response.json()["errors"]}
    assert field in errors, errors
    if field == "runs_per_dataset":
        assert "beyond this service's limit of 24 h" in errors[field] and "--max-campaign-hours" in errors[field]
    else:
        assert "outside the allowed range [0.001, 3600] s" in errors[field]
    assert submitter.get("/api/v1/campaigns").json()["campaigns"] == before
