"""A within-unit campaign's report (the spec's ``[units]``, issue 29): page 1 gives the within-unit decision on the line
after the between-unit one, and the observability section the analysis's within-unit statement, verbatim."""

from __future__ import annotations

import html as html_text
import re

import pypdf
import pytest
import xarray as xr

import campaigns
import reports
from campaigns.runner.synthetic import SYNTHETIC_CATALOG, synthetic_run

SPEC = """
name = "report_within_unit"
root_seed = 11
runs_per_dataset = 177
features = ["backlash_feature", "backlash_feature_true"]
[base]
parameters = "synthetic"
[execution]
isolation = "none"
[observability]
sweep = ["b0", "b1", "b2"]
[[datasets]]
name = "b0"
scene = "ds4"
conditions = { backlash = 0.0, preload = 0.0, external_force = 0.0 }
[[datasets]]
name = "b1"
scene = "ds2"
conditions = { backlash = 1e-6, preload = 0.0, external_force = 0.0 }
[[datasets]]
name = "b2"
scene = "ds2"
conditions = { backlash = 2e-6, preload = 0.0, external_force = 0.0 }
[[uncertainties]]
target = "synthetic.offset"
distribution = "uniform"
low = -1.0
high = 1.0
unit = "um"
[[uncertainties]]
target = "scene.room_temperature"
distribution = "uniform"
low = 15.0
high = 35.0
unit = "degC"
[units]
count = 59
repeats = 3
"""


@pytest.fixture(scope="module")
def within_unit_report(generated_at, tmp_path_factory):
    folder = tmp_path_factory.mktemp("within_unit_report")
    (folder / "spec.toml").write_text(SPEC)
    spec = campaigns.load_spec(folder / "spec.toml", catalog=SYNTHETIC_CATALOG)
    results = campaigns.run_campaign(spec, folder / "out", workers=1, progress=False, run_function=synthetic_run)
    campaigns.analyze(results, n_boot=200)
    return results, reports.build_report(results, out_dir=folder / "report", generated_at=generated_at)


def _text(html: str) -> str:
    return " ".join(html_text.unescape(re.sub(r"<[^>]+>", " ", html.replace("<wbr>", ""))).split())


def test_page_one_and_the_observability_section_give_the_within_unit_verdict(within_unit_report):
    results, paths = within_unit_report
    with xr.open_dataset(results.with_name("analysis.nc")) as analysis:
        statement = str(analysis["within_unit_requirement_statement"].sel(feature="backlash_feature").item())
        verdict = str(analysis["within_unit_requirement_verdict"].sel(feature="backlash_feature").item())
    decision = {"met": "GO", "not met": "NO-GO", "undetermined": "UNDETERMINED", "insufficient data": "NO DATA"}
    html = _text(paths["html"].read_text(encoding="utf-8"))
    executive = re.search(r'<section id="executive".*?</section>', paths["html"].read_text(encoding="utf-8"), re.S)
    assert f"{decision[verdict]} — within unit (the same unit tested as it wears)" in _text(executive.group(0))
    assert f"backlash_feature within unit: {statement}" in html
    page = " ".join(pypdf.PdfReader(paths["pdf"]).pages[0].extract_text().split())
    assert "within unit (the same unit tested as it wears)" in page
    # the between-unit line is still the first decision, and says it used one test per unit
    assert page.index("— Detect a 1 µm backlash") < page.index("— within unit")
    assert "one test per unit (repeat 0 of each of the 59 units)" in html
