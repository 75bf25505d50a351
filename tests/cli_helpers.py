"""Helpers shared by the command-line tests (importable: conftest modules are not)."""

from app.cli import main


def refused_in_one_line(capsys, argv: list[str], *words: str) -> str:
    """Run ``twin argv``: exit 2, one line on stderr holding every one of ``words``, no traceback; that line."""
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err, err
    for word in words:
        assert word in err, err
    return err
