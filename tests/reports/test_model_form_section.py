"""The report's model-form section and its page-1 sentence (reports/sections/model_form.py), on the synthetic model."""

from __future__ import annotations

import html
import re
from pathlib import Path

import pytest
import xarray as xr

import campaigns
import reports
from campaigns.runner.synthetic import SYNTHETIC_CATALOG, SyntheticModel
from reports.content import build
from reports.inputs import load_inputs
from reports.model import Callout, Table

SPEC = Path(__file__).parent / "data" / "campaign.toml"
#: A one-at-a-time variant of the synthetic sweep: 2 kN of external force on a 2e8 N/m stiffness adds 10 µm to
#: both features (campaigns/runner/synthetic.py), in every data set alike, so the sweep detects as before.
VARIANTS = "".join(
    f'\n[[datasets]]\nname = "{name}__external_force_2000"\nscene = "{name}"\n'
    f"conditions = {{ backlash = {backlash}, preload = 0.0, external_force = 2000.0 }}\n"
    for name, backlash in (("ds2", "80e-6"), ("ds4", "0.0"), ("ds6", "5e-6")))


@pytest.fixture(scope="module")
def model_form_report(tmp_path_factory, generated_at):
    out = tmp_path_factory.mktemp("model_form")
    spec_path = out / "spec.toml"
    spec_path.write_text(SPEC.read_text().replace("runs_per_dataset = 30", "runs_per_dataset = 60") + VARIANTS)
    spec = campaigns.load_spec(spec_path, catalog=SYNTHETIC_CATALOG)
    results = campaigns.run_campaign(spec, out / "campaign", workers=1, progress=False, run_function=SyntheticModel())
    campaigns.analyze(results)
    return build(load_inputs(results), generated_at.isoformat()), results


def test_the_report_renders_the_section_and_the_sentence(model_form_report, tmp_path, generated_at):
    report, results = model_form_report
    written = reports.build_report(results, out_dir=tmp_path, generated_at=generated_at)
    page = written["html"].read_text()
    sentence = next(c.text for c in report.executive if isinstance(c, Callout) and c.text.startswith("Model-form"))
    assert html.escape(sentence, quote=False) in page
    assert written["pdf"].stat().st_size > 0


def _section(report, key):
    return next(s for s in report.sections if s.key == key)


def test_page_one_names_the_assumption_with_the_numbers_of_model_form_nc(model_form_report):
    report, results = model_form_report
    with xr.open_dataset(results.with_name("model_form.nc"), engine="netcdf4") as table:
        headline = table.attrs["headline"]
    sentences = [k for k, c in enumerate(report.executive) if isinstance(c, Callout) and c.text.startswith("Model-f")]
    assert [report.executive[k].text for k in sentences] == [f"Model-form study: {headline}"]
    # on page 1 whatever the number of data sets: before the executive summary's first table
    assert sentences[0] < next(k for k, block in enumerate(report.executive) if isinstance(block, Table))
    assert headline.startswith("No assumption varied (external_force) changes a requirement verdict (2 compared); "
                               "external_force moves the features most: with external_force = 2000.0 instead of "
                               "0.0, the mean of backlash_feature")
    shift = float(re.search(r"shifts by ([+-][0-9.]+) µm", headline).group(1))
    assert shift == pytest.approx(10.0, abs=0.5)


def test_the_section_shows_the_verdicts_and_the_resolved_shifts(model_form_report):
    report, _ = model_form_report
    blocks = _section(report, "model_form").blocks
    verdicts, shifts = (b for b in blocks if isinstance(b, Table))
    assert [row[-1] for row in verdicts.rows] == ["unchanged", "unchanged"]
    assert [row[0] for row in shifts.rows] == ["ds2", "ds4", "ds6"]
    # 10 µm times the sampled gain (±10 % at 3 sigma) in every data set and feature, printed with its interval: the
    # mean of 60 runs is 10 µm to within 0.1 µm x 5
    values = [float(cell.split(" ")[0]) for row in shifts.rows for cell in row[1:]]
    assert values == pytest.approx([10.0] * 6, abs=0.5)
    assert all(" µm (" in cell for row in shifts.rows for cell in row[1:])


def test_a_campaign_that_is_no_model_form_study_says_so_and_adds_nothing_to_page_one(campaign, generated_at):
    report = build(load_inputs(campaign), generated_at.isoformat())
    (block,) = _section(report, "model_form").blocks
    assert isinstance(block, Callout) and block.text.startswith("This campaign is not a model-form study")
    assert not [c for c in report.executive if isinstance(c, Callout) and c.text.startswith("Model-form")]
