"""Issue 31, rows 1 and 2: one rule for every command that writes, checked command by command.

Never over a campaign's own files (results.nc, analysis.nc, spec.json, chunk files, the lock), not even with
--force; never over any other existing file without --force; the refusal names the file, before any work,
and the bytes on disk are unchanged.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from cli_helpers import refused_in_one_line

from campaigns.runner.files import CampaignError, campaign_file, check_output


@pytest.fixture
def campaign_dir(tmp_path) -> Path:
    """A finished campaign's directory as the runner lays it out (contents are stand-ins: the rule reads names)."""
    out = tmp_path / "campaign"
    (out / "chunks" / "0123456789abcdef").mkdir(parents=True)
    (out / "spec.json").write_text(json.dumps({"hash": "0" * 64, "canonical": {}}))
    (out / "results.nc").write_bytes(b"the campaign's results")
    (out / "analysis.nc").write_bytes(b"the campaign's analysis")
    (out / ".lock").write_bytes(b"")
    (out / "chunks" / "0123456789abcdef" / "d000-r000000-000009.npz").write_bytes(b"a chunk")
    return out


def _snapshot(directory: Path) -> dict[str, bytes]:
    return {str(p.relative_to(directory)): p.read_bytes() for p in sorted(directory.rglob("*")) if p.is_file()}


CAMPAIGN_FILES = ["results.nc", "spec.json", ".lock", "chunks/0123456789abcdef/d000-r000000-000009.npz",
                  "analysis.nc"]


@pytest.mark.parametrize("name", CAMPAIGN_FILES)
def test_simulate_never_writes_over_a_campaigns_files(campaign_dir, capsys, name):
    before = _snapshot(campaign_dir)
    for option in ("--out", "--plot"):
        for force in ([], ["--force"]):
            refused_in_one_line(capsys, ["simulate", "ds1", option, str(campaign_dir / name), *force],
                                str(campaign_dir / name), "even with --force")
    assert _snapshot(campaign_dir) == before


@pytest.mark.parametrize("name", CAMPAIGN_FILES[:4])
def test_analyze_never_writes_over_a_campaigns_files(campaign_dir, tmp_path, capsys, name):
    results = tmp_path / "elsewhere" / "results.nc"
    results.parent.mkdir()
    results.write_bytes(b"not read: the output is refused first")
    before = _snapshot(campaign_dir)
    refused_in_one_line(capsys, ["campaign", "analyze", str(results), "--out", str(campaign_dir / name), "--force"],
                        "no command writes over a campaign's own files")
    assert _snapshot(campaign_dir) == before


def test_analyze_may_replace_its_own_analysis_with_force_only(campaign_dir, capsys):
    assert check_output(campaign_dir / "analysis.nc", force=True, product="analysis.nc")
    with pytest.raises(CampaignError, match="already exists; pass --force"):
        check_output(campaign_dir / "analysis.nc", product="analysis.nc")


def test_replay_never_writes_over_a_campaigns_files(campaign_dir, capsys):
    before = _snapshot(campaign_dir)
    for name in ("results.nc", "spec.json", "analysis.nc"):
        refused_in_one_line(capsys, ["campaign", "replay", str(campaign_dir / "results.nc"), "--dataset", "ds1",
                                     "--run", "0", "--out", str(campaign_dir / name), "--force"],
                            str(campaign_dir / name))
    assert _snapshot(campaign_dir) == before


def test_replay_and_simulate_refuse_an_existing_file_without_force(tmp_path, capsys):
    existing = tmp_path / "run.nc"
    existing.write_bytes(b"an earlier run")
    refused_in_one_line(capsys, ["simulate", "ds1", "--out", str(existing)], "already exists; pass --force")
    refused_in_one_line(capsys, ["simulate", "ds1", "--plot", str(existing)], "already exists; pass --force")
    refused_in_one_line(capsys, ["campaign", "replay", str(tmp_path / "results.nc"), "--dataset", "ds1", "--run", "0",
                                 "--out", str(existing)], "already exists; pass --force")
    assert existing.read_bytes() == b"an earlier run"


def test_report_refuses_existing_files_and_a_file_for_its_directory(campaign_dir, tmp_path, capsys):
    (campaign_dir / "report.pdf").write_bytes(b"an earlier report")
    refused_in_one_line(capsys, ["report", str(campaign_dir / "results.nc"), "--out", str(campaign_dir)],
                        "report.pdf already exists; pass --force")
    refused_in_one_line(capsys, ["report", str(campaign_dir / "results.nc"), "--out", str(campaign_dir / "spec.json")],
                        "is not a directory")
    assert (campaign_dir / "report.pdf").read_bytes() == b"an earlier report"


def test_accuracy_and_chapter5_refuse_an_earlier_studys_files(tmp_path, capsys):
    (tmp_path / "work_precision.nc").write_bytes(b"an earlier study")
    refused_in_one_line(capsys, ["accuracy", "--quick", "--out", str(tmp_path)], "work_precision.nc already exists")
    (tmp_path / "fig5_6_efficiency_vs_force.png").write_bytes(b"an earlier figure")
    refused_in_one_line(capsys, ["chapter5", "--out", str(tmp_path)], "fig5_6_efficiency_vs_force.png already exists")
    assert (tmp_path / "work_precision.nc").read_bytes() == b"an earlier study"


def test_campaign_files_are_recognised_by_their_directory(campaign_dir, tmp_path):
    assert "results.nc of the campaign" in campaign_file(campaign_dir / "results.nc")
    assert "chunks/" in campaign_file(campaign_dir / "chunks" / "0123456789abcdef" / "new.npz")
    assert campaign_file(campaign_dir / "report.html") is None  # a derived file, not the campaign's own
    assert campaign_file(tmp_path / "results.nc") is None  # a results.nc outside a campaign directory
    link = tmp_path / "link.nc"
    link.symlink_to(campaign_dir / "results.nc")
    assert campaign_file(link) is not None  # reached through a symbolic link
