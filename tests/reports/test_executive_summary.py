"""Page 1 of the report decides: one GO / NO-GO / UNDETERMINED / NO DATA line per requirement from analysis.nc's
verdicts, bounds and n, with the runs that would decide an undetermined one; the comparison with another design in one
sentence; and an older analysis without a verdict says "not available" rather than a verdict the report composed."""

from __future__ import annotations

import re
import shutil

import numpy as np
import pypdf
import pytest
import xarray as xr

import reports


def _page_one(pdf) -> str:
    return " ".join(pypdf.PdfReader(pdf).pages[0].extract_text().split())


def _executive_html(html_path) -> str:
    html = html_path.read_text(encoding="utf-8").replace("<wbr>", "")
    section = re.search(r'<section id="executive".*?</section>', html, re.S).group(0)
    return " ".join(re.sub(r"<[^>]+>", " ", section).split())


def _contract_analysis(analysis: xr.Dataset) -> xr.Dataset:
    """The analysis with the CONTRACT.md verdict variables, as campaigns.analysis.campaign_analysis writes them (kept
    when present)."""
    if "requirement_statement" in analysis:
        return analysis
    features = [str(f) for f in analysis["feature"].values]
    verdicts = ["not met", "met", "undetermined"][: len(features)]
    n = int(analysis["n_used"].min())
    statements = [f"{v}: minimum detectable backlash {1.9 + k:.1f} µm "
                  f"(95 % bootstrap CI {1.4 + k:.1f}–{2.6 + k:.1f} µm; {n} ok runs per sweep data set, 3 data sets) "
                  "against the 1 µm requirement of Table 9.3"
                  for k, v in enumerate(verdicts)]
    sufficient = (analysis["n_used"] >= 10).astype(np.int8)
    return analysis.assign(
        requirement_verdict=("feature", np.array(verdicts, dtype=object)),
        requirement_statement=("feature", np.array(statements, dtype=object)),
        data_sufficient=sufficient.assign_attrs(flag_values=[0, 1], flag_meanings="insufficient sufficient"),
    ).assign_attrs(min_ok_runs=10, requirement=1e-6,
                   requirement_source="Table 9.3: minimum detectable linear backlash 1 µm")


@pytest.fixture(scope="module")
def with_verdicts(campaign, generated_at, tmp_path_factory):
    folder = tmp_path_factory.mktemp("verdicts")
    shutil.copyfile(campaign, folder / "results.nc")
    with xr.open_dataset(campaign.with_name("analysis.nc")) as stored:
        analysis = _contract_analysis(stored.load())
    analysis.to_netcdf(folder / "analysis.nc")
    return folder, reports.build_report(folder / "results.nc", out_dir=folder / "report", generated_at=generated_at)


def test_page_one_has_one_decision_line_per_requirement_and_each_n(with_verdicts):
    """Page 1 (PDF page 1 and the HTML summary) gives each measured feature's verdict as one decision line, in the
    analysis's verdict, with the ideal-sensor reading beside it; the data-set table gives each data set's runs used."""
    folder, paths = with_verdicts
    page, html = _page_one(paths["pdf"]), _executive_html(paths["html"])
    decisions = {"met": "GO", "not met": "NO-GO", "undetermined": "UNDETERMINED", "insufficient data": "NO DATA"}
    with xr.open_dataset(folder / "analysis.nc") as analysis:
        measured = [str(f) for f in analysis["feature"].values if not str(f).endswith("_true")]
        for feature in measured:
            verdict = str(analysis["requirement_verdict"].sel(feature=feature).item())
            line = f"{decisions[verdict]} — Detect a 1 µm backlash (Table 9.3) with"
            assert line in page and line in html, f"page 1 lacks the decision on {feature}"
        assert page.count(" — Detect a 1 µm backlash") == len(measured)  # one line per requirement
        for dataset in analysis["dataset"].values:
            used = min(int(analysis["n_used"].sel(dataset=dataset, feature=f)) for f in measured)
            row = re.search(rf"{dataset} .*?(\d+) of (\d+)", html)
            assert row and int(row.group(1)) == used, f"page 1 gives another n for {dataset}"
    assert "_true" not in page.split("Terms used on this page")[0]


def test_page_one_links_each_finding_to_its_section(with_verdicts):
    _, paths = with_verdicts
    html = paths["html"].read_text(encoding="utf-8")
    section = re.search(r'<section id="executive".*?</section>', html, re.S).group(0)
    for key in ("observability", "correlations", "failures", "fidelity"):
        assert f'href="#{key}"' in section
    assert "§1 Observability" in _page_one(paths["pdf"])  # the results first, provenance last (issue 42)


def test_an_older_analysis_gives_no_verdict(campaign, generated_at, tmp_path):
    """An analysis.nc written before requirement_verdict existed: page 1 says "not available", composes nothing."""
    shutil.copyfile(campaign, tmp_path / "results.nc")
    new = ["requirement_verdict", "requirement_statement", "data_sufficient", "first_order_index",
           "first_order_index_ci", "effect_size", "effect_size_ci", "minimum_detectable_backlash_ci"]
    with xr.open_dataset(campaign.with_name("analysis.nc")) as stored:
        old = stored.load().drop_vars(new, errors="ignore")
    old.attrs.pop("min_ok_runs", None)
    old.to_netcdf(tmp_path / "analysis.nc")
    paths = reports.build_report(tmp_path / "results.nc", out_dir=tmp_path / "report", generated_at=generated_at)
    page = _page_one(paths["pdf"])
    assert "Requirement verdict: not available" in page
    assert not re.search(r"\b(GO|NO-GO|UNDETERMINED) — Detect", page)  # no decision composed without a verdict
    assert "a rank correlation, not an effect size" in page  # the influences fall back to |Spearman ρ|, labelled


def test_an_unresolved_index_is_not_listed_as_an_influence(campaign, generated_at, tmp_path):
    """A first-order index whose bootstrap interval includes 0 is noise at this sample size: page 1 names no
    tolerance as an influence and says that none is resolved, instead of ranking the noise."""
    shutil.copyfile(campaign, tmp_path / "results.nc")
    with xr.open_dataset(campaign.with_name("analysis.nc")) as stored:
        analysis = _contract_analysis(stored.load())
    assert "first_order_index_ci" in analysis
    lower = analysis["first_order_index_ci"].sel(bound="lower")
    analysis["first_order_index_ci"] = analysis["first_order_index_ci"].where(
        analysis["bound"] != "lower", -np.abs(lower) - 0.01)
    analysis.to_netcdf(tmp_path / "analysis.nc")
    paths = reports.build_report(tmp_path / "results.nc", out_dir=tmp_path / "report", generated_at=generated_at)
    summary = _executive_html(paths["html"])
    assert "first-order index is resolved above zero (95 % bootstrap interval) in any data set" in summary
    assert " moves it by " not in summary


def test_page_one_decides_each_design_limit_over_the_loops(campaign, generated_at, tmp_path):
    """Page 1 gives one decision per design limit over every loop, from the analysis's margin_limit_* variables:
    the worst loop decides, "0 of 350 runs" undetermined reads as what it is, with the runs that would decide it."""
    shutil.copyfile(campaign, tmp_path / "results.nc")
    with xr.open_dataset(campaign.with_name("analysis.nc")) as stored:
        analysis = _contract_analysis(stored.load())
    checks = ["current_loop_phase_margin", "speed_loop_phase_margin", "current_loop_gain_margin",
              "speed_loop_gain_margin"]
    verdicts = ["met", "not met", "undetermined", "met"]
    counts = [[0, 400], [12, 400], [0, 350], [0, 350]]
    bounds = [[0.0, 0.0092], [0.0156, 0.052], [0.0, 0.0105], [0.0, 0.0105]]
    analysis = analysis.assign(
        margin_limit_verdict=("limit_check", np.array(verdicts, dtype=object),
                              {"control_limits": '{"phase_margin_min": 30, "gain_margin_min": 6, '
                                                 '"peak_sensitivity_max": 2, "max_fraction_beyond": 0.01}'}),
        margin_limit_statement=("limit_check", np.array([f"{v}: statement {k}" for k, v in enumerate(verdicts)],
                                                        dtype=object)),
        margin_limit_counts=(("limit_check", "count"), np.array(counts, dtype=np.int32)),
        margin_limit_fraction=("limit_check", np.array([c[0] / c[1] for c in counts])),
        margin_limit_fraction_ci=(("limit_check", "bound"), np.array(bounds)),
        margin_limit_runs_to_decide=("limit_check", np.array([np.nan, np.nan, 368.0, np.nan])),
    ).assign_coords(limit_check=("limit_check", np.array(checks, dtype=object)))
    analysis.to_netcdf(tmp_path / "analysis.nc")
    paths = reports.build_report(tmp_path / "results.nc", out_dir=tmp_path / "report", generated_at=generated_at)
    text = _executive_html(paths["html"])
    assert ("NO-GO — Phase margin at least 30° in every loop (current, speed): the speed loop has 12 of 400 runs "
            "below it (3 %; at least 1.6 % at 95 % confidence, 1 % of runs allowed below it).") in text
    assert ("UNDETERMINED — Gain margin at least 6 dB in every loop (current, speed): no run of 350 in the current "
            "loop is below it, but 350 runs show the share below it only to be under 1.1 % (95 % confidence), not "
            "under the 1 % allowed; about 368 runs with the same share would decide GO.") in text
    section = re.search(r'<section id="executive".*?</section>', paths["html"].read_text(encoding="utf-8"), re.S)
    assert 'href="#control_robustness"' in section.group(0)


def test_page_one_says_when_a_campaign_has_no_loop_margins(report):
    """The synthetic campaign runs no bench loops: page 1 says no design limit is checked, not a verdict."""
    assert "carry no loop margins" in _executive_html(report["html"]).replace("<wbr>", "")


def test_a_comparison_report_has_its_sentence_on_page_one_and_its_section(campaign, generated_at, tmp_path):
    """`report A --against B`: B is A's runs with the backlash feature 0.5 µm larger (paired run by run, the same
    draws): page 1 gives the comparison's one sentence, the largest resolved change in the feature's words and in the
    prefix that shows it, and the section "A against B" tabulates every shift alike (the unshifted feature as identical
    in every run)."""
    (tmp_path / "b").mkdir()
    with xr.open_dataset(campaign) as stored:
        other = stored.load()
    other["backlash_feature"] = other["backlash_feature"] + 0.5e-6
    other.to_netcdf(tmp_path / "b" / "results.nc")
    shutil.copyfile(campaign.with_name("analysis.nc"), tmp_path / "b" / "analysis.nc")  # the same verdicts
    paths = reports.build_report(campaign, out_dir=tmp_path / "report", generated_at=generated_at,
                                 against_path=tmp_path / "b" / "results.nc")
    text = _executive_html(paths["html"])
    assert ("report_test against report_test (paired run by run): every verdict the same (2 compared); the largest "
            "resolved change is the backlash feature f_b (Eq. 9.12) in ") in text
    assert re.search(r"f_b \(Eq. 9.12\) in ds\d, -500 nm \(95 % interval -500 … -500 nm\) in its mean", text)
    html = paths["html"].read_text(encoding="utf-8").replace("<wbr>", "")
    section = re.search(r'<section id="comparison".*?</section>', html, re.S).group(0)
    assert "report_test against report_test" in section and "-500 nm (95 % interval -500 … -500 nm)" in section
    assert "0 (95 % interval 0 … 0: identical in every run)" in section  # backlash_feature_true: not shifted
    assert "the backlash feature f_b (Eq. 9.12), ideal sensors" in section  # the features in page 1's words
    assert "the backlash feature f_b (Eq. 9.12): minimum detectable fault size against the requirement" in section
    assert not re.search(r"\de-\d|0\.000\d", section)  # no exponent, no 0.000x: the prefix that shows the value
    assert "The two specs differ in their name and description only." in section  # the same spec, runs shifted
