"""Fixtures of the report tests: one small synthetic campaign with failures, and its report."""

from __future__ import annotations

from datetime import UTC, datetime
from pathlib import Path

import pytest

import campaigns
import reports
from campaigns.runner.synthetic import SYNTHETIC_CATALOG, SyntheticModel

SPEC = Path(__file__).parent / "data" / "campaign.toml"
#: Runs that fail, one per failure kind the runner records without waiting for a timeout.
FAULTS = {("ds2", 3): "raise", ("ds4", 5): "nan", ("ds6", 7): "diverge"}
GENERATED_AT = datetime(2026, 1, 2, 3, 4, 5, tzinfo=UTC)


@pytest.fixture(scope="session")
def campaign(tmp_path_factory) -> Path:
    """``results.nc`` and ``analysis.nc`` of the test campaign (runs in a few seconds on one worker)."""
    out = tmp_path_factory.mktemp("campaign")
    spec = campaigns.load_spec(SPEC, catalog=SYNTHETIC_CATALOG)
    results = campaigns.run_campaign(spec, out, workers=1, progress=False, run_function=SyntheticModel(faults=FAULTS))
    campaigns.analyze(results)
    return results


@pytest.fixture(scope="session")
def generated_at() -> datetime:
    """The pinned timestamp of the test reports."""
    return GENERATED_AT


@pytest.fixture(scope="session")
def report(campaign, generated_at, tmp_path_factory) -> dict[str, Path]:
    """The campaign's report (HTML and PDF) with a pinned timestamp."""
    return reports.build_report(campaign, out_dir=tmp_path_factory.mktemp("report"), generated_at=generated_at)
