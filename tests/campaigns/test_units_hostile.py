"""Issue 39: a unit string that is no unit gets one ValueError naming it, never the parser's own exception (pint reads
units with Python's tokenizer and evaluator, which raise TokenError, AssertionError, ZeroDivisionError...; on the
service those were HTTP 500s). The probes of the issue, then a property over random short texts."""

from __future__ import annotations

import pytest
from campaign_helpers import load, write_spec
from hypothesis import given, settings
from hypothesis import strategies as st

from campaigns.runner.spec import SpecError
from campaigns.units import MAX_UNIT_LENGTH, conversion

PROBES = ["deg)", "(deg", "m*", "1/0", "m**", "**", "m/", "()", "{", "\x00", "m**(1/0)", "km**400"]


@pytest.mark.parametrize("unit", PROBES)
def test_a_broken_unit_is_one_value_error_naming_it(unit):
    with pytest.raises(ValueError) as info:
        conversion(unit, "m")
    assert type(info.value) is ValueError and repr(unit) in str(info.value)
    assert "\n" not in str(info.value)


def test_a_text_longer_than_any_unit_is_refused_unparsed_and_shown_cut():
    with pytest.raises(ValueError) as info:
        conversion("(" * 100_000 + "m" + ")" * 100_000, "m")  # the parser would recurse 100 000 deep
    message = str(info.value)
    assert "200001 characters" in message and f"at most {MAX_UNIT_LENGTH} characters" in message
    assert len(message) < 300


def test_good_units_still_convert():
    assert conversion("um", "m") == pytest.approx((1e-6, 0.0))
    assert conversion("degC", "K") == pytest.approx((1.0, 273.15))
    assert conversion("kg·m²", "kg*m**2") == pytest.approx((1.0, 0.0))


@settings(max_examples=300, deadline=None, derandomize=True, database=None)
@given(st.text(alphabet=st.sampled_from("m()*/^0123456789.+-e degCkK%µ[]{}_,;:'\"\\#!<>=|&~"), max_size=12))
def test_conversion_raises_only_value_error_on_any_short_text(text):
    """Texts built from the characters that unit syntax, Python's tokenizer and pint's grammar care about."""
    try:
        scale, offset = conversion(text, "m")
    except ValueError as exc:
        assert type(exc) is ValueError  # not a subclass leaking the parser's error
        return
    assert scale != 0.0 and abs(scale) < float("inf") and abs(offset) < float("inf")


@settings(max_examples=100, deadline=None, derandomize=True, database=None)
@given(st.text(max_size=8))
def test_conversion_raises_only_value_error_on_any_unicode_text(text):
    try:
        conversion(text, "K")
    except ValueError as exc:
        assert type(exc) is ValueError


def test_a_spec_row_with_a_broken_unit_is_a_spec_problem(tmp_path):
    text = ('[[uncertainties]]\ntarget = "synthetic.inert"\ndistribution = "uniform"\nlow = 0.0\nhigh = 1.0\n'
            'unit = "deg)"\n')
    with pytest.raises(SpecError) as info:
        load(write_spec(tmp_path, text, append=True))
    assert any("'deg)'" in p for p in info.value.problems), info.value.problems
