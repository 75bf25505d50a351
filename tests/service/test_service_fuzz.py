"""A bounded fuzz of every route of the service (issue 39): no request, however malformed, gets a 5xx.

schemathesis is not in ``requirements/test.lock``; this is Hypothesis over the application's own routes (every
operation of its OpenAPI schema, and the web pages the schema leaves out), in this process with no executor
(nothing runs). Requests mix valid and unknown tokens, cookies and foreign origins, declared and stray query
parameters, path segments that try traversals, and bodies that are bytes, JSON, forms, or a spec with one value
replaced. The generation is derandomized with a fixed number of examples and no deadline: the same
requests on every machine, however loaded.
"""

from __future__ import annotations

import json
import re
from pathlib import Path
from urllib.parse import quote, urlencode

import pytest
from fastapi.routing import APIRoute
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from service_helpers import SPEC, LocalService

import campaigns
from app.service import api, web
from app.service.auth import COOKIE_NAME

#: Enough to reach each route with each kind of body several times (its time: docs/service.md, Hostile input).
EXAMPLES = 300
#: The specs a request may submit with one value replaced: the test spec (it extends the thesis study) and the
#: thesis study itself (its tolerance rows carry units, distributions, sources).
BASES = [SPEC.read_text().splitlines(), (Path(campaigns.__file__).parent / "specs" / "thesis_backlash.toml")
         .read_text(encoding="utf-8").splitlines()]


@pytest.fixture(scope="module")
def local(tmp_path_factory):
    # no queue limit in the way: a refusal for a full queue comes before the validation the fuzz is after
    service = LocalService(tmp_path_factory.mktemp("fuzz") / "data", max_queued_per_user=10**6)
    for name, role in (("reader", "read"), ("submitter", "submit"), ("admin", "admin")):
        service.client(name, role)
    accepted = service.client("submitter").post("/api/v1/campaigns", content=SPEC.read_text(), params={"runs": 1})
    assert accepted.status_code == 201, accepted.text
    service.campaign_id = accepted.json()["id"]
    return service


def operations() -> list[tuple[str, str, tuple[str, ...]]]:
    """``(method, path template, query parameter names)`` of every route of the service: the API's, the web
    pages' (both routers are included without a prefix), the schema, the static files."""
    found = [("GET", "/api/v1/openapi.json", ()), ("GET", "/static/{path}", ())]
    for route in (*api.router.routes, *web.router.routes):
        assert isinstance(route, APIRoute)
        names = tuple(p.alias for p in route.dependant.query_params)
        found += [(method, route.path, names) for method in sorted(route.methods)]
    return found


def test_the_fuzz_covers_every_operation_of_the_schema(local):
    schema = local.app.openapi()["paths"]
    documented = {(method.upper(), path) for path, item in schema.items() for method in item}
    assert documented <= {(method, path) for method, path, _ in operations()}


texts = st.text(st.characters(codec="utf-8"), max_size=24)
numbers = st.one_of(st.integers(-(2**70), 2**70), st.floats(allow_nan=True, allow_infinity=True))
toml_values = st.one_of(
    numbers.map(lambda v: json.dumps(v).replace("NaN", "nan").replace("Infinity", "inf")),
    texts.map(json.dumps),
    st.sampled_from(['"deg)"', '"(deg"', '"m*"', '"1/0"', '"20 um"', '"3 mrad"', "[]", "{}", "true", '""',
                     '"../../../tmp/x"', "[[[[[[[[[[[[[[[[[[[[1]]]]]]]]]]]]]]]]]]]", "1" * 5000]),
)


@st.composite
def spec_with_one_value_replaced(draw) -> str:
    lines = list(draw(st.sampled_from(BASES)))
    # a seeded Random spreads the choice over the whole spec (Hypothesis's own draws start at the first line)
    k = draw(st.randoms(use_true_random=True)).choice(
        [k for k, line in enumerate(lines) if re.match(r"^\s*[\w.\"-]+\s*=", line)])
    lines[k] = lines[k].split("=", 1)[0] + "= " + draw(toml_values)
    return "\n".join(lines)


# bodies as (content type, bytes)
specs = spec_with_one_value_replaced()
toml_bodies = specs.map(lambda text: ("application/toml", text.encode()))
json_bodies = st.fixed_dictionaries({"spec": st.one_of(specs, texts)}, optional={"runs": numbers, "seed": numbers}) \
    .map(lambda d: ("application/json", json.dumps(d).encode()))
form_bodies = st.fixed_dictionaries({"spec": specs}, optional={"runs": texts, "seed": texts, "token": texts,
                                                               "next": texts}) \
    .map(lambda d: ("application/x-www-form-urlencoded", urlencode(d).encode()))
raw_bodies = st.tuples(st.sampled_from(["application/toml", "application/json", "application/x-www-form-urlencoded",
                                        "text/plain", "multipart/form-data"]), st.binary(max_size=200))
BODIES = {"/api/v1/campaigns": st.one_of(toml_bodies, toml_bodies, json_bodies, raw_bodies),
          "/submit": st.one_of(form_bodies, form_bodies, raw_bodies)}
other_bodies = st.one_of(form_bodies, raw_bodies)
query_values = st.one_of(texts, numbers.map(str), st.sampled_from(["", "demo.toml", "//evil.example", "/campaigns"]))
segments = st.one_of(texts, st.sampled_from(["..", ".", "spec", "report.html", "results.nc", "%2e%2e", "a/../b"]))


#: The operations that read a body, drawn half of the time (a plain draw over all would reach them 1 in 10).
SUBMISSIONS = [("POST", "/api/v1/campaigns", ("runs", "seed")), ("POST", "/submit", ()), ("POST", "/login", ())]


@st.composite
def requests(draw, local) -> dict:
    method, template, names = draw(st.one_of(st.sampled_from(SUBMISSIONS), st.sampled_from(operations())))
    method = draw(st.sampled_from([method] * 9 + ["GET", "POST", "PUT", "DELETE", "HEAD", "OPTIONS"]))
    ids = st.sampled_from([local.campaign_id, "000000000000"])
    path = re.sub(r"\{(\w+)\}", lambda m: quote(draw(ids if m[1] == "campaign_id" else segments), safe=""), template)
    query = draw(st.dictionaries(st.sampled_from([*names, "runs", "seed", "limit", "example", "next", "apikey", "x"]),
                                 query_values, max_size=3))
    headers = {}
    # mostly one who may submit, with a bearer token: the requests that reach the validation
    token = draw(st.sampled_from([local.tokens["submitter"]] * 4 + [None, *local.tokens.values(), "bt_unknown"]))
    how = draw(st.sampled_from(["bearer"] * 3 + ["cookie", "malformed"]))
    if token and how == "bearer":
        headers["authorization"] = f"Bearer {token}"
    elif token and how == "cookie":
        headers["cookie"] = f"{COOKIE_NAME}={token}"
    elif token:
        headers["authorization"] = draw(st.sampled_from(["Bearer", "Basic " + token, "Bearer  ", token]))
    headers["content-type"], content = draw(BODIES.get(template, other_bodies))
    headers.update(draw(st.sampled_from([{}, {"sec-fetch-site": "same-origin"}, {"origin": "http://testserver"},
                                         {"origin": "http://evil.example"}, {"sec-fetch-site": "cross-site"}])))
    return {"method": method, "url": path, "params": query, "headers": headers, "content": content}


@settings(max_examples=EXAMPLES, deadline=None, derandomize=True, database=None,
          # too_slow would make the test depend on the machine's speed; the spec bodies are large by design
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(data=st.data())
def test_no_request_gets_a_5xx(local, data):
    request = data.draw(requests(local))
    response = local.client().request(**request)  # a new client each time: no cookie carried from one to the next
    assert response.status_code < 500, (request, response.status_code, response.text[:500])
