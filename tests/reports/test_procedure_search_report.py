"""The report of a test-procedure search (``search.nc`` of ``twin procedure search``): page 1 gives the statement
verbatim in its verdict's tone and the ranked table; the file's text is escaped; numbers read at the precision their
bounds resolve; a file that breaks the contract is refused with the variable named."""

from __future__ import annotations

import json
import math
import re
from datetime import UTC, datetime

import numpy as np
import pypdf
import pytest
import xarray as xr

import reports
from reports.errors import ReportError

GENERATED_AT = datetime(2026, 1, 2, 3, 4, 5, tzinfo=UTC)
STATEMENT = ("met: the best procedure p03 detects a backlash growth of 0.84 µm (95 % interval 0.71 … 0.97 µm) "
             "<script>alert(1)</script> {#$ not markup} within 120 s")
KNOBS = ["preload", "external_force", "amplitude", "frequency", "cycles", "dwell", "zero_procedure"]
CANDIDATES = ["p00", "p01", "p02", "p03", "p04", "p05"]
NAN, INF = math.nan, math.inf


def search_dataset() -> xr.Dataset:
    """Six candidates, two features: p00 the reference, p03 (best) and p01 finalists, p05 without a resolved score."""
    c, cf = ("candidate",), ("candidate", "feature")
    score = np.array([2.3456e-6, 1.2345e-6, 3.1e-6, 0.8412345e-6, 40.0e-6, NAN])
    low = np.array([1.1e-6, 1.01e-6, 2.5e-6, 0.7123e-6, 31.0e-6, NAN])
    high = np.array([4.9e-6, 1.49e-6, 3.8e-6, 0.9678e-6, 52.0e-6, NAN])
    notes = np.array([[""] * 2] * 5 + [["no resolved level in 3 repeats", "no resolved level in 3 repeats"]],
                     dtype=object)

    def knob(values, units, long_name):
        return c, np.asarray(values, dtype=float), {"units": units, "long_name": long_name}

    data = {
        "knob_preload": knob([2000, 1000, 0, 1500, 500, 3000], "N", "preload force of the nut pair"),
        "knob_external_force": knob([4000, 0, 2000, 0, 0, 1000], "N", "external axial force"),
        "knob_amplitude": knob([5e-3, 2e-3, 1e-3, 3e-3, 0.5e-3, 4e-3], "m", "motion amplitude"),
        "knob_frequency": knob([0.5, 1.0, 2.0, 0.25, 4.0, 0.5], "Hz", "motion frequency"),
        "knob_cycles": knob([10, 20, 5, 30, 1000, 10], "1", "motion cycles"),
        "knob_dwell": knob([1.0, 0.5, 0.0, 2.0, 0.0, 1.0], "s", "dwell at each reversal"),
        "knob_zero_procedure": (c, np.array(["thesis", "preloaded", "thesis", "preloaded", "thesis", "thesis"],
                                            dtype=object), {"long_name": "zero procedure"}),
        "test_duration": (c, np.array([60.0, 40.0, 12.5, 3600.0, 250.0, 30.0]), {"units": "s"}),
        "reference": (c, np.array([1, 0, 0, 0, 0, 0], dtype=np.int8)),
        "screening_estimate": (cf, np.stack([score, score * 1.3], axis=1), {"units": "m"}),
        "screening_low": (cf, np.stack([low, low * 1.3], axis=1), {"units": "m"}),
        "screening_high": (cf, np.stack([high, high * 1.3], axis=1), {"units": "m"}),
        "screening_note": (cf, notes),
        "best_feature": (c, np.array(["backlash_hysteresis"] * 5 + [""], dtype=object)),
        "score": (c, score, {"units": "m"}),
        "score_low": (c, low, {"units": "m"}),
        "score_high": (c, high, {"units": "m"}),
        "round_reached": (c, np.array([1, 2, 1, 2, 0, 0], dtype=np.int32)),
        "finalist": (c, np.array([0, 1, 0, 1, 0, 0], dtype=np.int8)),
        "within_unit_low": (c, np.array([NAN, 1e-6, NAN, 0.5e-6, NAN, NAN]), {"units": "m"}),
        "within_unit_high": (c, np.array([NAN, INF, NAN, 1e-6, NAN, NAN]), {"units": "m"}),
        "within_unit_verdict": (c, np.array(["", "not met", "", "met", "", ""], dtype=object)),
        "within_unit_statement": (c, np.array(["", "not met: above 1 µm", "", "met: 0.5–1 µm", "", ""],
                                              dtype=object)),
        "pareto": (c, np.array([0, 1, 1, 1, 0, 0], dtype=np.int8)),
        "rank": (c, np.array([3, 2, 4, 1, 5, 6], dtype=np.int32)),
        "difference_to_best": (c, np.array([1.5e-6, 0.39e-6, 2.26e-6, NAN, 39.2e-6, NAN]), {"units": "m"}),
        "difference_low": (c, np.array([0.3e-6, 0.12e-6, 1.7e-6, NAN, 30.1e-6, NAN]), {"units": "m"}),
        "difference_high": (c, np.array([4.0e-6, 0.71e-6, 2.9e-6, NAN, 51.0e-6, NAN]), {"units": "m"}),
        "evidence": (c, np.array([f"candidates/{p}" for p in CANDIDATES], dtype=object)),
        "rerun": (c, np.array([f"twin campaign run search/candidates/{p}/campaign.toml --out candidates/{p} "
                               f"--workers 4" for p in CANDIDATES], dtype=object)),
    }
    attrs = {
        "name": "backlash_procedures", "description": "Which procedure shows backlash growth soonest?",
        "fault": "backlash", "fault_unit": "m", "requirement": 1e-6, "requirement_source": "Table 9.3",
        "statement": STATEMENT, "verdict": "met", "best": "p03", "knobs": json.dumps(KNOBS),
        "search_spec": 'name = "backlash_procedures"\nfault = "backlash"\n[knobs]\npreload = [0, 3000]\n',
        "plan": "round 0: 6 candidates screened at 2 µm on 20 units x 3 repeats\nround 1: 3 kept\nfinal: 2 finalists",
        "root_seed": 7, "units": 20, "repeats": 3, "screening_level": 2e-6, "Conventions": "CF-1.8",
        "history": "twin procedure search search.toml",
    }
    return xr.Dataset(data, coords={"candidate": CANDIDATES, "feature": ["backlash_hysteresis", "backlash_feature"]},
                      attrs=attrs)


@pytest.fixture(scope="module")
def search_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("search") / "search.nc"
    search_dataset().to_netcdf(path, engine="netcdf4")
    return path


@pytest.fixture(scope="module")
def built(search_file, tmp_path_factory):
    return reports.build_search_report(search_file, tmp_path_factory.mktemp("search_report"),
                                       generated_at=GENERATED_AT)


@pytest.fixture(scope="module")
def html(built) -> str:
    return built["html"].read_text(encoding="utf-8")


@pytest.fixture(scope="module")
def pages(built) -> list[str]:
    return [" ".join(page.extract_text().split()) for page in pypdf.PdfReader(built["pdf"]).pages]


def _rows(html: str) -> list[str]:
    table = html[html.index('id="table-1"'):]
    table = table[:table.index("</table>")]
    return re.findall(r"<tr[^>]*>(.*?)</tr>", table[table.index("<tbody>"):], flags=re.S)


def test_the_three_files_are_written(built):
    assert set(built) == {"html", "pdf", "chart"}
    assert [p.name for p in (built["html"], built["pdf"], built["chart"])] == ["search_report.html",
                                                                                 "search_report.pdf", "pareto.png"]
    assert built["pdf"].read_bytes().startswith(b"%PDF")
    assert built["chart"].read_bytes().startswith(b"\x89PNG")


def test_page_one_gives_the_statement_verdict_and_best_before_the_table(pages):
    first = pages[0]
    assert "Test-procedure search: backlash_procedures" in first
    assert "backlash growth" in first and "1 µm" in first
    table = first.index("Table 1")
    assert 0 <= first.index(" ".join(STATEMENT.split())) < table
    assert 0 <= first.index("GO — met:") < table  # the decision, then the statement that starts with its verdict
    assert 0 <= first.index("Best procedure: p03") < table
    assert "reference" in first


def test_the_table_is_in_rank_order_with_the_reference_marked(html, pages):
    rows = _rows(html)
    ids = [re.findall(r"<td>(.*?)</td>", row, flags=re.S)[1] for row in rows]
    assert [re.sub(r"<wbr>", "", i) for i in ids] == ["p03", "p01", "p00 (reference)", "p02", "p04", "p05"]
    first = pages[0]
    positions = [first.index(name, first.index("Table 1")) for name in ("p03", "p01", "p00 (reference)", "p02")]
    assert positions == sorted(positions)


def test_the_statement_is_in_the_tone_of_its_verdict(html):
    assert '<div class="callout good">GO — met: the best procedure p03' in html


def test_a_preload_loss_search_reads_in_newtons_with_its_verdict(tmp_path):
    search = search_dataset()
    for name in ("score", "score_low", "score_high", "difference_to_best", "difference_low", "difference_high",
                 "within_unit_low", "within_unit_high", "screening_estimate", "screening_low", "screening_high"):
        search[name] = search[name] * 1e8  # 0.84 µm -> 84 N
    search.attrs.update(fault="preload_loss", fault_unit="N", requirement=200.0, verdict="not met",
                        statement="no procedure resolves a preload loss of 200 N within 1 h")
    path = tmp_path / "search.nc"
    search.to_netcdf(path, engine="netcdf4")
    html = reports.build_search_report(path, tmp_path / "out", generated_at=GENERATED_AT)["html"].read_text("utf-8")
    assert "preload loss; requirement 200 N" in html
    assert ('<div class="callout bad">NO-GO (not met) — no procedure resolves a preload loss of 200 N within 1 h'
            in html)
    assert "84 N (95 % interval 71 … 97 N)" in _rows(html)[0]


def test_the_file_text_is_escaped_in_html(html):
    assert "<script>alert(1)</script>" not in html
    assert "&lt;script&gt;alert(1)&lt;/script&gt;" in html
    assert "{#$ not markup}" in html


def test_unresolved_values_show_a_dash(html):
    rows = _rows(html)
    best, p05 = rows[0], rows[-1]
    cells = [c.strip() for c in re.findall(r"<td>(.*?)</td>", p05, flags=re.S)]
    assert cells[-1] == "—"  # difference to best
    assert cells[-5].startswith("— (no resolved level")  # screening estimate, with the file's note
    assert re.findall(r"<td>(.*?)</td>", best, flags=re.S)[-1] == "—"  # the best's difference to itself
    assert not re.search(r"\bnan\b", html, flags=re.I)


def test_numbers_read_at_the_precision_their_bounds_resolve(html):
    rows = _rows(html)
    assert "0.84 µm (95 % interval 0.71 … 0.97 µm)" in rows[0]
    assert "0.8412" not in html
    assert "2.3 µm (95 % interval 1.1 … 4.9 µm)" in rows[2]
    assert "0.5–1 µm" in rows[0]  # the best's within-unit bracket
    assert "&gt; 1 µm" in rows[1]  # a bracket above the largest level
    assert "3600" in rows[0] and "1000" in rows[4]  # durations and cycles without an exponent


def test_reproduction_lists_every_rerun_command_and_the_spec(html, pages):
    for p in CANDIDATES:
        assert f"twin campaign run search/candidates/{p}/campaign.toml" in html
    assert "<pre>" in html and "[knobs]" in html and "round 1: 3 kept" in html
    assert any("preload = [0, 3000]" in page for page in pages[1:])


def test_a_missing_variable_is_named(tmp_path):
    path = tmp_path / "search.nc"
    search_dataset().drop_vars("score_high").to_netcdf(path, engine="netcdf4")
    with pytest.raises(ReportError) as error:
        reports.build_search_report(path, tmp_path / "out")
    assert error.value.path == path
    assert "'score_high'" in str(error.value) and str(path) in str(error.value)
    assert not (tmp_path / "out" / "search_report.pdf").exists()


def test_a_missing_file_is_refused(tmp_path):
    with pytest.raises(ReportError, match="not found"):
        reports.build_search_report(tmp_path / "absent.nc", tmp_path / "out")
