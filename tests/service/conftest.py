"""One real server for the API and browser tests (the kill test starts its own)."""

from __future__ import annotations

import pytest
from service_helpers import Server, create_token


@pytest.fixture(scope="session")
def service(tmp_path_factory):
    """A started server and a token per role: ``reader``, ``submitter``, ``other`` (a second submitter), ``admin``."""
    data = tmp_path_factory.mktemp("service-data")
    tokens = {"reader": create_token(data, "reader", "read"), "submitter": create_token(data, "submitter", "submit"),
              "other": create_token(data, "other", "submit"), "admin": create_token(data, "admin", "admin")}
    server = Server(data, tmp_path_factory.mktemp("service-log") / "server.log").start()
    server.tokens = tokens
    yield server
    server.stop()
    log = server.log()
    for token in tokens.values():
        assert token not in log, "a token appeared in the server's log"
