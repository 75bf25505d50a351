"""Fixtures of the campaign tests: one reference campaign shared by several tests."""

from __future__ import annotations

from pathlib import Path

import pytest
from campaign_helpers import SYNTHETIC_SPEC, load

import campaigns
from campaigns.runner.synthetic import synthetic_run


@pytest.fixture(scope="session")
def reference_results(tmp_path_factory) -> Path:
    """The synthetic campaign run once on two workers, without interruption."""
    out = tmp_path_factory.mktemp("reference")
    return campaigns.run_campaign(load(SYNTHETIC_SPEC), out, workers=2, progress=False, run_function=synthetic_run)


@pytest.fixture(scope="session")
def single_worker_results(tmp_path_factory) -> Path:
    """The same synthetic campaign on one worker."""
    out = tmp_path_factory.mktemp("single_worker")
    return campaigns.run_campaign(load(SYNTHETIC_SPEC), out, workers=1, progress=False, run_function=synthetic_run)
