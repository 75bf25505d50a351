"""The report's Fidelity section with the session-13 audit: a data set not re-run (identical) in its own row, a
torque's figures in mN·m, the overall line verbatim."""

from __future__ import annotations

import dataclasses

import pytest

from campaigns.bench.fidelity_audit import IDENTICAL
from reports.content import build
from reports.inputs import load_inputs
from reports.model import Callout, Table

_LENGTH = ("met: mean shift +0.0018 µm (95 % t interval -0.0100 µm to +0.0136 µm, n = 59; tolerance ±0.0500 µm): met; "
           "sd ratio 1.0100 (sd 0.4000 µm against 0.3960 µm; 95 % jackknife interval 0.9800 to 1.0400, n = 59; "
           "tolerance 0.90 to 1.10): met")
_TORQUE = ("met: mean shift +0.2100 mN·m (95 % t interval +0.1000 mN·m to +0.3200 mN·m, n = 59; tolerance "
           "±1.4300 mN·m): met; sd ratio 1.0000 (sd 4.1000 mN·m against 4.1000 mN·m; 95 % jackknife interval 0.9900 "
           "to 1.0100, n = 59; tolerance 0.90 to 1.10): met")
_OVERALL = ("met: auto is within the tolerances of full fidelity (mean shift, standard deviation) on ds2 (59 paired "
            "runs each) and identical on the other 3 data set(s), whose automatic choice is the full model (not "
            "re-run)")


@pytest.fixture(scope="module")
def fidelity(campaign):
    inputs = load_inputs(campaign)
    names = [str(d) for d in inputs.results["dataset"].values]
    results = inputs.results.assign_attrs(
        fidelity_audit=_OVERALL, fidelity_audit_runs="59",
        # the format of campaigns.bench.fidelity_audit.summary_attrs
        **{f"fidelity_audit_{names[0]}": f"speedup x1.70; backlash_feature: {_LENGTH}; max paired 0.0257 µm, MC error "
                                         f"0.0862 µm, KS p 1.00 | drag_torque_feature: {_TORQUE}; max paired 0.9000 "
                                         "mN·m, MC error 1.0500 mN·m, KS p 0.99"},
        **{f"fidelity_audit_{d}": IDENTICAL for d in names[1:]})
    report = build(dataclasses.replace(inputs, results=results), "T")
    return names, next(s for s in report.sections if s.key == "fidelity")


def test_identical_data_sets_have_their_row_and_a_torque_its_unit(fidelity):
    names, section = fidelity
    audit = next(b for b in section.blocks if isinstance(b, Table) and b.caption.startswith("Automatic against full"))
    assert audit.rows[:2] == ((names[0], "backlash_feature", _LENGTH, "0.0257 µm", "0.0862 µm", "1.00", "1.70"),
                              (names[0], "drag_torque_feature", _TORQUE, "0.9000 mN·m", "1.0500 mN·m", "0.99", ""))
    assert audit.rows[2:] == tuple((d, "every feature", IDENTICAL, "–", "–", "–", "–") for d in names[1:])
    said = next(b for b in section.blocks if isinstance(b, Callout))
    assert said.text == f"Audit result: {_OVERALL}."
