"""Issue 39: hostile and careless input to the command line gets one line on stderr and exit 2, never a traceback,
and leaves nothing half-written."""

from __future__ import annotations

from pathlib import Path

import pytest
from cli_helpers import refused_in_one_line

from app.cli import main


def test_a_taken_token_name_is_one_line_and_the_first_token_stands(tmp_path, capsys):
    data = str(tmp_path / "data")
    assert main(["serve", "token", "create", "alice", "--role", "read", "--data", data]) == 0
    capsys.readouterr()
    refused_in_one_line(capsys, ["serve", "token", "create", "alice", "--role", "admin", "--data", data],
                        "a token named 'alice' exists already", "revoke it first")
    assert main(["serve", "token", "list", "--data", data]) == 0
    assert capsys.readouterr().out == "alice\tread\n"  # the refused one changed nothing


@pytest.mark.parametrize("name", ["ali\nce", "tab\there", "", "x" * 101])
def test_a_token_name_with_a_newline_or_out_of_bounds_is_one_line(tmp_path, capsys, name):
    err = refused_in_one_line(capsys, ["serve", "token", "create", name, "--role", "read", "--data", str(tmp_path)],
                              "a token name is 1-100 printable characters")
    assert name not in err or name == ""  # shown quoted (the newline as \n), a long one by its length
    assert main(["serve", "token", "list", "--data", str(tmp_path)]) == 0
    assert capsys.readouterr().out == ""


@pytest.mark.parametrize("name, words", [
    ("../../../tmp/x", ("name: '../../../tmp/x' holds '.' '/'",)),
    ("x" * 1_000_000, ("name: a name of 1000000 characters; at most 100",)),
])
def test_a_campaign_name_cannot_leave_out_or_overflow_a_file_name(tmp_path, capsys, monkeypatch, name, words):
    """Issue 39: ``name = "../../../tmp/x"`` wrote outside out/, a 1 MB name ended in ENAMETOOLONG: the spec is
    refused before any work, in the spec's one message (SpecError), without echoing the name."""
    import json

    import campaigns

    spec = tmp_path / "spec.toml"
    demo = Path(campaigns.__file__).parent / "specs" / "demo.toml"
    spec.write_text(f'extends = "{demo}"\nname = {json.dumps(name)}\n')
    work = tmp_path / "work"
    work.mkdir()
    monkeypatch.chdir(work)
    assert main(["campaign", "run", str(spec), "--runs", "2"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err and len(err) < 1000 and err.startswith("twin: error: invalid campaign spec"), err
    for word in words:
        assert word in err
    assert not list(work.iterdir()) and not (tmp_path / "tmp").exists()  # nothing written anywhere
