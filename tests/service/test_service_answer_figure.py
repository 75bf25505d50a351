"""Issue 42, item 4: the service's campaign page shows the report's page-1 figure (detection probability against the
fault size per sweep level, the requirement, the verdicts) with its caption, escaped where the user's text appears.

In this process (nothing runs): the runner's drawing step on a synthetic sweep analysis, then the page and the file as
the server serves them."""

from __future__ import annotations

import json

import numpy as np
import pytest
import xarray as xr
from service_helpers import LocalService

from app.service.runner import answer_figure
from app.service.submission import ANSWER_FIGURE, output_dir
from campaigns.analysis.campaign_analysis import analysis_dataset
from reports.detection import detection_answer

#: A requirement source as a spec may word it ([observability] requirement_source is free text): markup for the page,
#: and a pair of $ around what matplotlib cannot read as mathtext (drawn as written, the figure would fail otherwise).
HOSTILE = '<script>alert("x")</script> costs $x^$'
LEVELS = (0.0, 0.5e-6, 2e-6)
RUNS = 60


def _sweep_analysis() -> xr.Dataset:
    """A backlash sweep 0, 0.5, 2 µm, 60 runs per level, feature noise 0.1 µm: its analysis, with the hostile source."""
    rng = np.random.default_rng(0)
    names = [f"b{i}" for i in range(len(LEVELS))]
    f = np.asarray(LEVELS)[:, None] + rng.normal(0, 0.1e-6, (len(LEVELS), RUNS))
    spec = {"name": "answer", "description": "", "base": {"scene": "nominal"},
            "datasets": [{"name": n, "conditions": {"backlash": b}} for n, b in zip(names, LEVELS, strict=True)],
            "observability": {"sweep": names}}
    results = xr.Dataset(
        {"f": (("dataset", "run"), f, {"role": "feature", "units": "m"}),
         "p.gain": (("dataset", "run"), rng.uniform(-1, 1, f.shape), {"role": "sampled", "units": "1"}),
         "status": (("dataset", "run"), np.full(f.shape, "ok", dtype=object)),
         "failure_reason": (("dataset", "run"), np.full(f.shape, "", dtype=object)),
         "wall_time": (("dataset", "run"), np.ones(f.shape)),
         "condition_backlash": ("dataset", np.asarray(LEVELS), {"units": "m"})},
        coords={"dataset": names, "run": np.arange(RUNS)},
        attrs={"spec_json": json.dumps({"spec": spec}), "spec_hash": "ab" * 32})
    analysis = analysis_dataset(results, n_boot=20, sensitivity_boot=10)
    analysis.attrs.update(requirement=1e-6, requirement_source=HOSTILE)
    return analysis


@pytest.fixture(scope="module")
def analysis():
    return _sweep_analysis()


def _done_campaign(local: LocalService, analysis: xr.Dataset) -> str:
    """A campaign recorded as done, its figure drawn by the runner's step and its caption in the summary."""
    campaign_id = "c0ffee"
    assert local.registry.add_campaign(campaign_id, "answer", "ab" * 32, 3 * RUNS, {}, "someone")
    out = output_dir(local.registry.campaign_dir(campaign_id))
    out.mkdir(parents=True)
    caption = answer_figure(analysis, out)
    statement = f"f: {analysis['requirement_statement'].sel(feature='f').item()} ({HOSTILE})"  # the user's text
    local.registry.update(campaign_id, state="done", summary={"statements": [statement], "warnings": [],
                                                              "figure_caption": caption + HOSTILE})
    return campaign_id


def test_the_runner_draws_the_report_figure_and_the_page_shows_it_escaped(tmp_path, analysis):
    local = LocalService(tmp_path / "data")
    campaign_id = _done_campaign(local, analysis)
    reader = local.client("reader", "read")
    page = reader.get(f"/campaigns/{campaign_id}")
    assert page.status_code == 200
    url = f"/api/v1/campaigns/{campaign_id}/files/{ANSWER_FIGURE}"
    assert f'<img src="{url}"' in page.text
    caption = page.text.split('<figure class="answer" id="answer">', 1)[1].split("</figure>", 1)[0]
    assert "Detection probability against backlash" in caption
    assert "<script>alert" not in page.text and "&lt;script&gt;alert" in caption  # the user's text, shown as text
    served = reader.get(url)
    assert served.status_code == 200 and served.headers["content-type"] == "image/png"
    png, _ = detection_answer(analysis)
    assert served.content == png  # the very figure of the report's page 1
    assert not list(output_dir(local.registry.campaign_dir(campaign_id)).glob("*.partial"))


def test_an_analysis_without_a_sweep_draws_nothing_and_the_page_says_nothing_of_it(tmp_path, analysis):
    out = tmp_path / "out"
    out.mkdir()
    assert answer_figure(analysis.drop_dims("sweep_point"), out) == ""
    assert not (out / ANSWER_FIGURE).exists()
    local = LocalService(tmp_path / "data")
    assert local.registry.add_campaign("beef", "plain", "ab" * 32, 1, {}, "someone")
    local.registry.update("beef", state="done", summary={"statements": [], "warnings": [], "figure_caption": ""})
    page = local.client("reader", "read").get("/campaigns/beef")
    assert page.status_code == 200 and 'class="answer"' not in page.text
