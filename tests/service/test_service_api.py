"""The service over HTTP, against a real server: auth, validation, limits, files, a campaign to done."""

from __future__ import annotations

import subprocess
import sys
import tomllib

import pytest
import xarray as xr
from service_helpers import SPEC, client, twin, wait_final

from app.service.submission import ANSWER_FIGURE, BUILTIN_SPECS
from campaigns.analysis.campaign_analysis import summary
from reports.detection import detection_answer


def test_health_needs_no_token_and_the_api_needs_one(service):
    anonymous = client(service, None)
    assert anonymous.get("/health").json()["status"] == "ok"
    response = anonymous.get("/api/v1/campaigns")
    assert response.status_code == 401
    assert response.headers["www-authenticate"] == "Bearer"
    assert client(service, "bt_not-a-token").get("/api/v1/campaigns").status_code == 401
    malformed = anonymous.get("/api/v1/campaigns", headers={"Authorization": f"Basic {service.tokens['reader']}"})
    assert malformed.status_code == 401
    assert anonymous.get("/api/v1/openapi.json").json()["info"]["title"] == "BenchTwin robustness service"
    assert anonymous.get("/", follow_redirects=False).headers["location"].startswith("/login")


def test_roles_are_enforced(service):
    reader = client(service, service.tokens["reader"])
    assert reader.get("/api/v1/campaigns").status_code == 200
    response = reader.post("/api/v1/campaigns", content=SPEC.read_text())
    assert response.status_code == 403
    assert "submit" in response.json()["detail"]
    # a campaign may be cancelled by its submitter or an admin, not by another submitter
    submitted = client(service, service.tokens["submitter"]).post("/api/v1/campaigns", content=SPEC.read_text(),
                                                                 params={"runs": 1, "seed": 99})
    assert submitted.status_code == 201, submitted.text
    campaign_id = submitted.json()["id"]
    assert submitted.json()["overrides"] == {"runs_per_dataset": 1, "root_seed": 99}
    assert client(service, service.tokens["other"]).post(f"/api/v1/campaigns/{campaign_id}/cancel").status_code == 403
    assert reader.post(f"/api/v1/campaigns/{campaign_id}/cancel").status_code == 403
    admin = client(service, service.tokens["admin"])
    assert admin.post(f"/api/v1/campaigns/{campaign_id}/cancel").status_code == 200
    assert wait_final(admin, campaign_id)["state"] == "cancelled"
    assert admin.post(f"/api/v1/campaigns/{campaign_id}/cancel").status_code == 409


BROKEN_SPEC = """
name = ""
root_seed = -3
runs_per_dataset = 0
features = ["backlash_feature", "no_such_feature"]
[execution]
isolation = "thread"
[[datasets]]
name = "a"
scene = "ds2"
[[datasets]]
name = "a"
scene = "ds9"
[[uncertainties]]
target = "no.such.parameter"
distribution = "uniform"
low = 2.0
high = 1.0
"""
#: Field paths of BROKEN_SPEC's problems (every one must be reported).
BROKEN_PATHS = ["name", "root_seed", "runs_per_dataset", "features", "execution.isolation", "datasets[1].scene",
                "datasets", "uncertainties[0]"]


def test_an_invalid_spec_gets_every_error_with_its_path_and_nothing_is_queued(service):
    submitter = client(service, service.tokens["submitter"])
    before = submitter.get("/api/v1/campaigns").json()["campaigns"]
    campaign_dirs = sorted((service.data / "campaigns").glob("*")) if (service.data / "campaigns").exists() else []
    response = submitter.post("/api/v1/campaigns", content=BROKEN_SPEC, headers={"Content-Type": "application/toml"})
    assert response.status_code == 422
    errors = response.json()["errors"]
    paths = [e["path"] for e in errors]
    for path in BROKEN_PATHS:
        assert path in paths, f"{path} missing from {errors}"
    assert all(e["message"] for e in errors)
    assert f"{len(errors)} problem(s)" in response.json()["detail"]
    # a spec reaching for the server's files is refused too, with the rest of its problems
    response = submitter.post("/api/v1/campaigns", json={"spec": BROKEN_SPEC.replace('"ds2"', '"/etc/passwd"')})
    assert response.status_code == 422
    assert "datasets[0].scene" in [e["path"] for e in response.json()["errors"]]
    assert "root_seed" in [e["path"] for e in response.json()["errors"]]
    response = submitter.post("/api/v1/campaigns", content='extends = "../../registry.sqlite3"\nname = "x"\n')
    assert response.status_code == 422
    assert response.json()["errors"][0]["path"] == "extends"
    response = submitter.post("/api/v1/campaigns", content="name = [unclosed")
    assert response.status_code == 422 and "TOML" in response.json()["errors"][0]["message"]
    assert submitter.get("/api/v1/campaigns").json()["campaigns"] == before
    assert (sorted((service.data / "campaigns").glob("*")) if (service.data / "campaigns").exists() else []) \
        == campaign_dirs
    assert not any((service.data / "staging").glob("*"))


def test_an_oversized_spec_is_413_and_nothing_is_queued(service):
    submitter = client(service, service.tokens["submitter"])
    before = submitter.get("/api/v1/campaigns").json()["campaigns"]
    huge = SPEC.read_text() + "\n# padding\n" * 30_000
    assert submitter.post("/api/v1/campaigns", content=huge).status_code == 413

    def chunks():  # no Content-Length: the limit holds while the body streams in
        for _ in range(40):
            yield b"#" * 10_000 + b"\n"

    assert submitter.post("/api/v1/campaigns", content=chunks()).status_code == 413
    assert submitter.get("/api/v1/campaigns").json()["campaigns"] == before


def _identical_data(a: xr.Dataset, b: xr.Dataset) -> None:
    """Every data variable and coordinate equal bit for bit, except the machine-dependent run wall times."""
    assert sorted(a.variables) == sorted(b.variables)
    for name in a.variables:
        if name == "wall_time":
            continue
        x, y = a[name].values, b[name].values
        assert x.dtype == y.dtype and x.shape == y.shape, name
        if x.dtype.kind == "f":
            assert x.tobytes() == y.tobytes(), name
        else:
            assert (x == y).all(), name


def test_a_small_thesis_campaign_runs_to_done_and_matches_the_cli(service, tmp_path):
    submitter = client(service, service.tokens["submitter"])
    text = SPEC.read_text()
    response = submitter.post("/api/v1/campaigns", content=text, params={"runs": 2})
    assert response.status_code == 201, response.text
    campaign_id = response.json()["id"]
    assert response.headers["location"] == f"/api/v1/campaigns/{campaign_id}"
    record = wait_final(submitter, campaign_id)
    assert record["state"] == "done", record["error"]
    assert record["progress"]["runs_done"] == record["progress"]["runs_total"] == 4
    reader = client(service, service.tokens["reader"])
    files = {}
    for name in ("results.nc", "analysis.nc", "report.html", "report.pdf", "spec", "spec.json"):
        response = reader.get(f"/api/v1/campaigns/{campaign_id}/files/{name}")
        assert response.status_code == 200, name
        files[name] = tmp_path / "served" / name
        files[name].parent.mkdir(exist_ok=True)
        files[name].write_bytes(response.content)
    assert files["spec"].read_text() == text
    assert files["report.pdf"].read_bytes().startswith(b"%PDF")
    assert "<html" in files["report.html"].read_text()[:500].lower()
    # the verdict lines shown are the analysis's own, verbatim, with the caption of the report's page-1 figure
    with xr.open_dataset(files["analysis.nc"]) as analysis:
        statements, warnings = summary(analysis)
        answer = detection_answer(analysis.load())
    figures = [{"name": ANSWER_FIGURE, "caption": answer[1]}] if answer is not None else []
    assert record["summary"] == {"statements": statements, "warnings": warnings, "figures": figures}
    assert statements
    figure = reader.get(f"/api/v1/campaigns/{campaign_id}/files/{ANSWER_FIGURE}")
    assert (figure.status_code, figure.content) == ((200, answer[0]) if answer is not None else (404, figure.content))

    # the CLI on the same spec and runs (its extends resolved beside it, as the service does)
    local_spec = tmp_path / "cli-spec" / "small_thesis.toml"
    local_spec.parent.mkdir()
    local_spec.write_text(text)
    parent = tomllib.loads(text)["extends"]
    (local_spec.parent / parent).write_text((BUILTIN_SPECS / parent).read_text())
    cli = twin("campaign", "run", str(local_spec), "--runs", "2", "--workers", "1",
               "--out", str(tmp_path / "cli"))
    assert cli.returncode == 0, cli.stderr
    with xr.open_dataset(files["results.nc"]) as served, xr.open_dataset(tmp_path / "cli" / "results.nc") as local:
        assert served.attrs["spec_hash"] == local.attrs["spec_hash"] == record["spec_hash"]
        _identical_data(served.load(), local.load())
        assert (served["status"].values == "ok").all()


TRAVERSALS = ["../registry.sqlite3", "..%2F..%2Fregistry.sqlite3", "%2e%2e/%2e%2e/registry.sqlite3", "runner.log",
              ".lock", "input", "out", "submitted.toml", "results.nc/..", "RESULTS.NC"]


@pytest.mark.parametrize("name", TRAVERSALS)
def test_a_file_outside_the_list_or_a_traversal_is_404(service, name):
    reader = client(service, service.tokens["reader"])
    campaigns_list = reader.get("/api/v1/campaigns").json()["campaigns"]
    campaign_id = campaigns_list[-1]["id"] if campaigns_list else "none"
    response = reader.get(f"/api/v1/campaigns/{campaign_id}/files/{name}")
    assert response.status_code == 404
    assert b"SQLite" not in response.content
    assert reader.get("/api/v1/campaigns/..%2F..%2F/files/results.nc").status_code == 404
    assert reader.get("/api/v1/campaigns/../../registry.sqlite3").status_code == 404


def test_the_server_binds_to_loopback_by_default():
    result = subprocess.run([sys.executable, "-m", "app.cli", "serve", "--help"], capture_output=True, text=True)
    assert "default 127.0.0.1" in result.stdout
