"""The thesis study samples the EXTENSION rows of Table 9.5 (issue 33); the thesis-only study keeps the table as it is.

``thesis_backlash.toml`` lists Table 9.5's rows, then the extension rows; ``thesis_backlash_table_9_5_only.toml``
extends it with the thesis rows only, a copy (a spec that extends another replaces its list whole): this checks the
copy, and that the extension rows are exactly the parameters tagged ``table_9_5_extension``.
"""

from pathlib import Path

import pytest

import campaigns
import twin
from campaigns.runner.spec import read_spec

SPECS = Path(campaigns.__file__).parent / "specs"
EXTENSION = "EXTENSION of Table 9.5"


@pytest.fixture(scope="module")
def rows():
    return read_spec(SPECS / "thesis_backlash.toml")["uncertainties"], read_spec(
        SPECS / "thesis_backlash_table_9_5_only.toml")["uncertainties"]


def test_the_thesis_only_spec_has_the_thesis_rows_first_and_unchanged(rows):
    extended, thesis_only = rows
    assert len(thesis_only) == 38  # every row of Table 9.5
    assert extended[:len(thesis_only)] == thesis_only  # same rows, same order: the two studies are paired run by run
    assert not any(EXTENSION in row["source"] for row in thesis_only)


def test_the_extension_rows_are_the_tagged_parameters_and_come_last(rows):
    extended, thesis_only = rows
    added = extended[len(thesis_only):]
    assert added and all(row["source"].startswith(EXTENSION) for row in added)
    bench = twin.load_parameters("bench")
    tagged = {name for name in bench if bench[name].table_9_5_extension}
    assert {row["target"] for row in added} == tagged


@pytest.mark.parametrize("name", ["thesis_backlash", "thesis_backlash_table_9_5_only", "thesis_backlash_preloaded",
                                  "observability", "demo"])
def test_the_specs_validate_with_their_rows_inside_the_parameter_bounds(name):
    spec = campaigns.load_spec(SPECS / f"{name}.toml")
    expected = 38 if name == "thesis_backlash_table_9_5_only" else 38 + 10
    assert len(spec.distributions()) == expected
