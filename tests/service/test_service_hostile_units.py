"""Issue 39's unit probes through the service: a spec row whose unit pint cannot read ('deg)', '(deg', 'm*', '1/0'
raised TokenError, AssertionError or ZeroDivisionError inside campaigns.units.conversion, an HTTP 500) is one 422
naming the row's unit, and nothing is queued."""

from __future__ import annotations

import pytest
from service_helpers import SPEC, LocalService

PROBES = ["deg)", "(deg", "m*", "1/0"]


@pytest.fixture(scope="module")
def local(tmp_path_factory):
    return LocalService(tmp_path_factory.mktemp("units") / "data")


@pytest.mark.parametrize("unit", PROBES)
def test_an_unreadable_unit_in_a_spec_row_is_one_422_naming_it(local, unit):
    text = SPEC.read_text() + f'''
[[uncertainties]]
target = "scene.room_temperature"
distribution = "uniform"
low = 15.0
high = 35.0
unit = "{unit}"
'''
    api = local.client("alice")
    response = api.post("/api/v1/campaigns", content=text)
    assert response.status_code == 422, response.text
    messages = " ".join(e["message"] for e in response.json()["errors"])
    assert repr(unit) in messages and "Traceback" not in messages, messages
    assert api.get("/api/v1/campaigns").json()["campaigns"] == []
