"""Issue 42, item 4: the service's campaign page shows the report's page-1 figure of each fault sweep (detection
probability against the fault size per sweep level, the requirement, the verdicts) with its caption, escaped where
the user's text appears; the API serves the figures the campaign's summary lists and no other name.

In this process (nothing runs): the runner's drawing step on synthetic sweep analyses (one backlash sweep; a backlash
and a preload-loss sweep), then the page and the files as the server serves them."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr
from service_helpers import LocalService

from app.service.runner import answer_figures
from app.service.submission import ANSWER_FIGURE, output_dir
from campaigns.analysis.campaign_analysis import analysis_dataset
from reports.detection import detection_answer, sweep_views

#: A requirement source as a spec may word it ([observability] requirement_source is free text): markup for the page,
#: and a pair of $ around what matplotlib cannot read as mathtext (drawn as written, the figure would fail otherwise).
HOSTILE = '<script>alert("x")</script> costs $x^$'
RUNS = 60
#: Data sets: backlash [m], preload [N]. The backlash sweep b0, b1, b2 (0, 0.5, 2 µm); the preload sweep b0, p800,
#: p600 (losses 0, 200, 400 N from the healthy 1000 N).
DATASETS = {"b0": (0.0, 1000.0), "b1": (0.5e-6, 1000.0), "b2": (2e-6, 1000.0), "p800": (0.0, 800.0),
            "p600": (0.0, 600.0)}
BACKLASH = {"sweep": ["b0", "b1", "b2"]}
PRELOAD = {"sweep": ["b0", "p800", "p600"], "condition": "preload", "reference": "b0", "requirement": 200.0,
           "requirement_source": HOSTILE}


def _sweep_analysis(sweeps: list[dict]) -> xr.Dataset:
    """The analysis of feature f = backlash + preload loss x 1e-8 m/N + noise 0.1 µm, 60 runs per data set, along
    ``sweeps``, with the hostile source on the first sweep."""
    rng = np.random.default_rng(0)
    names = [n for n in DATASETS if any(n in s["sweep"] for s in sweeps)]
    backlash, preload = (np.array([DATASETS[n][k] for n in names]) for k in (0, 1))
    f = (backlash + (1000.0 - preload) * 1e-8)[:, None] + rng.normal(0, 0.1e-6, (len(names), RUNS))
    spec = {"name": "answer", "description": "", "base": {"scene": "nominal"},
            "datasets": [{"name": n, "conditions": {"backlash": b, "preload": p}}
                         for n, b, p in zip(names, backlash, preload, strict=True)],
            "observability": sweeps[0], "further_sweeps": sweeps[1:]}
    results = xr.Dataset(
        {"f": (("dataset", "run"), f, {"role": "feature", "units": "m"}),
         "p.gain": (("dataset", "run"), rng.uniform(-1, 1, f.shape), {"role": "sampled", "units": "1"}),
         "status": (("dataset", "run"), np.full(f.shape, "ok", dtype=object)),
         "failure_reason": (("dataset", "run"), np.full(f.shape, "", dtype=object)),
         "wall_time": (("dataset", "run"), np.ones(f.shape)),
         "condition_backlash": ("dataset", backlash, {"units": "m"}),
         "condition_preload": ("dataset", preload, {"units": "N"})},
        coords={"dataset": names, "run": np.arange(RUNS)},
        attrs={"spec_json": json.dumps({"spec": spec}), "spec_hash": "ab" * 32})
    analysis = analysis_dataset(results, n_boot=20, sensitivity_boot=10)
    analysis.attrs.update(requirement=1e-6, requirement_source=HOSTILE)
    return analysis


@pytest.fixture(scope="module")
def one_sweep():
    return _sweep_analysis([BACKLASH])


@pytest.fixture(scope="module")
def two_sweeps():
    return _sweep_analysis([BACKLASH, PRELOAD])


def _done_campaign(local: LocalService, analysis: xr.Dataset, campaign_id: str = "c0ffee") -> str:
    """A campaign recorded as done, its figures drawn by the runner's step and listed in the summary."""
    assert local.registry.add_campaign(campaign_id, "answer", "ab" * 32, 3 * RUNS, {}, "someone")
    out = output_dir(local.registry.campaign_dir(campaign_id))
    out.mkdir(parents=True)
    figures = answer_figures(analysis, out)
    statement = f"f: {analysis['requirement_statement'].sel(feature='f').item()} ({HOSTILE})"  # the user's text
    local.registry.update(campaign_id, state="done", summary={
        "statements": [statement], "warnings": [],
        "figures": [{**figure, "caption": figure["caption"] + HOSTILE} for figure in figures]})
    return campaign_id


def _figures_on(page: str) -> list[tuple[str, str]]:
    """``(img src, caption)`` of each answer figure on a campaign page, in page order."""
    shown = []
    for block in page.split('<figure class="answer" id="answer')[1:]:
        block = block.split("</figure>", 1)[0]
        shown.append((block.split('<img src="', 1)[1].split('"', 1)[0],
                      block.split("<figcaption>", 1)[1].split("</figcaption>", 1)[0]))
    return shown


def test_one_sweep_draws_the_report_figure_and_the_page_shows_it_escaped(tmp_path, one_sweep):
    local = LocalService(tmp_path / "data")
    campaign_id = _done_campaign(local, one_sweep)
    reader = local.client("reader", "read")
    page = reader.get(f"/campaigns/{campaign_id}")
    assert page.status_code == 200
    url = f"/api/v1/campaigns/{campaign_id}/files/{ANSWER_FIGURE}"
    [(src, caption)] = _figures_on(page.text)
    assert src == url and "Detection probability against backlash" in caption
    assert "<script>alert" not in page.text and "&lt;script&gt;alert" in caption  # the user's text, shown as text
    served = reader.get(url)
    assert served.status_code == 200 and served.headers["content-type"] == "image/png"
    png, _ = detection_answer(one_sweep)
    assert served.content == png  # the very figure of the report's page 1
    assert not list(output_dir(local.registry.campaign_dir(campaign_id)).glob("*.partial"))


def test_two_sweeps_draw_two_figures_each_served_and_shown(tmp_path, two_sweeps):
    local = LocalService(tmp_path / "data")
    campaign_id = _done_campaign(local, two_sweeps)
    reader = local.client("reader", "read")
    record = reader.get(f"/api/v1/campaigns/{campaign_id}").json()
    names = ["detection.png", "detection_preload.png"]
    assert [f["name"] for f in record["summary"]["figures"]] == names
    assert [n for n in record["files"] if n.endswith(".png")] == names
    page = reader.get(f"/campaigns/{campaign_id}").text
    shown = _figures_on(page)
    assert [src for src, _ in shown] == [f"/api/v1/campaigns/{campaign_id}/files/{n}" for n in names]
    assert "against backlash" in shown[0][1] and "against preload loss" in shown[1][1]
    assert all("&lt;script&gt;alert" in caption for _, caption in shown) and "<script>alert" not in page
    for name in names:  # listed with the report and the data files too
        assert f'<a href="/api/v1/campaigns/{campaign_id}/files/{name}">{name}</a>' in page
    for (key, view), name in zip(sweep_views(two_sweeps), names, strict=True):
        served = reader.get(f"/api/v1/campaigns/{campaign_id}/files/{name}")
        assert (served.status_code, served.headers["content-type"]) == (200, "image/png"), key
        assert served.content == detection_answer(view)[0]


@pytest.mark.parametrize("name", ["detection_backlash.png", "detection_preload.png.partial", "detection.PNG",
                                  "detection_.png", "chunks", "../out/detection.png"])
def test_a_figure_name_the_summary_does_not_list_is_404(tmp_path, one_sweep, name):
    """A one-sweep campaign has detection.png alone: another sweep's name, the partial file, another spelling are
    unknown names, even where a file of that name lies in the output."""
    local = LocalService(tmp_path / "data")
    campaign_id = _done_campaign(local, one_sweep)
    (output_dir(local.registry.campaign_dir(campaign_id)) / "detection_backlash.png").write_bytes(b"\x89PNG planted")
    response = local.client("reader", "read").get(f"/api/v1/campaigns/{campaign_id}/files/{name}")
    assert response.status_code == 404


def test_a_summary_entry_that_is_no_figure_name_is_not_served(tmp_path, one_sweep):
    """The file list derives from the summary, and only a figure's name counts as one: an entry naming another file
    of the campaign (the runner's log) serves nothing."""
    local = LocalService(tmp_path / "data")
    campaign_id = _done_campaign(local, one_sweep)
    summary = local.registry.campaign(campaign_id)["summary"]
    summary["figures"].append({"name": "runner.log", "caption": ""})
    local.registry.update(campaign_id, summary=summary)
    reader = local.client("reader", "read")
    assert reader.get(f"/api/v1/campaigns/{campaign_id}/files/runner.log").status_code == 404
    assert "runner.log" not in reader.get(f"/campaigns/{campaign_id}").text


def test_an_analysis_without_a_sweep_draws_nothing_and_the_page_says_nothing_of_it(tmp_path, one_sweep):
    out = tmp_path / "out"
    out.mkdir()
    assert answer_figures(one_sweep.drop_dims("sweep_point"), out) == []
    assert not list(out.iterdir())
    local = LocalService(tmp_path / "data")
    assert local.registry.add_campaign("beef", "plain", "ab" * 32, 1, {}, "someone")
    local.registry.update("beef", state="done", summary={"statements": [], "warnings": [], "figures": []})
    page = local.client("reader", "read").get("/campaigns/beef")
    assert page.status_code == 200 and 'class="answer"' not in page.text
