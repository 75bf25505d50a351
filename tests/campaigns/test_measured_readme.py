"""Issue 39: the README's measured-test commands run as written on the shipped sample (examples/measured/).

The commands are read from the README itself and run in a folder laid out as the README's user has it: the sample
under examples/measured/, and the campaigns they name (out/observability, out/thesis) stood in by the small sweep
campaign of the measured-test fixture (a 7 x 100-run observability campaign is not for the test suite).
"""

from __future__ import annotations

import re
import shlex
import shutil

import xarray as xr
from measured_helpers import ROOT, SAMPLE

from app.cli import main
from campaigns.workflows.diagnosis import diagnose
from campaigns.workflows.measured import read_measured


def readme_measured_commands() -> list[list[str]]:
    """The README's `twin measure ...` and `twin report ... --measured` lines, as argument lists after `twin`."""
    commands = []
    for line in ROOT.joinpath("README.md").read_text(encoding="utf-8").splitlines():
        if line.startswith(".venv/bin/twin ") and (" measure " in line or "--measured" in line):
            words = shlex.split(line, comments=True)
            commands.append(words[1:])
    return commands


def test_the_readme_names_the_shipped_sample():
    commands = readme_measured_commands()
    assert [c[:2] for c in commands] == [["measure", "import"], ["measure", "diagnose"],
                                         ["report", "out/thesis/results.nc"]]
    for word in (w for c in commands for w in c if w.startswith("examples/")):
        assert ROOT.joinpath(word).is_file(), word


def test_the_readme_measured_test_commands_run_as_written(measured_campaign, tmp_path, monkeypatch, capsys):
    shutil.copytree(SAMPLE, tmp_path / "examples" / "measured", ignore=shutil.ignore_patterns("*.py", "__pycache__"))
    for name in ("observability", "thesis"):
        shutil.copytree(measured_campaign.results.parent, tmp_path / "out" / name)
    monkeypatch.chdir(tmp_path)
    printed = []
    for argv in readme_measured_commands():
        assert main(argv) == 0, argv
        printed.append(capsys.readouterr().out)
    imported, diagnosed, reported = printed
    assert "10001 acquisition instants (1 ms)" in imported and "wrote out/bench_run_measured.nc" in imported
    test = read_measured(tmp_path / "out" / "bench_run_measured.nc")
    found = diagnose(test, xr.open_dataset(tmp_path / "out" / "observability" / "results.nc").load())
    assert f"verdict: {found.verdict}\n" in diagnosed
    assert re.search(r"wrote html report: .*report\.html", reported)
    html = (tmp_path / "out" / "thesis" / "report" / "report.html").read_text(encoding="utf-8").replace("<wbr>", "")
    assert "Measured test bench run 2026-11-20 #3: " in re.sub(r"<[^>]+>", " ", html)
