"""Monte Carlo campaign runner: spec, sampling, execution, storage, analysis.

Entry points (the ``twin campaign`` CLI calls these):

* :func:`load_spec` — read and validate a campaign spec (TOML), against the bench twin's catalog by default;
* :func:`run_campaign` — run or resume it on dask (the bench twin by default), then its fidelity audit, write
  ``results.nc``;
* :func:`analyze` — correlations, separation and observability, write ``analysis.nc``.

See ``docs/campaigns.md``. The names are imported on first use so that a
sandbox process (:mod:`campaigns.runner.sandbox`), which needs only
:mod:`campaigns.runner.runs` and the run model, does not pay for dask and scipy.
"""

import importlib

_EXPORTS = {
    "analyze": "campaigns.analysis.campaign_analysis",
    "run_campaign": "campaigns.bench.campaign",
    "load_spec": "campaigns.bench.campaign",
    "CampaignSpec": "campaigns.runner.spec",
    "SpecError": "campaigns.runner.spec",
    "HALF_RANGE_SIGMAS": "campaigns.units",
    "CampaignError": "campaigns.runner.storage",
}

__all__ = list(_EXPORTS)


def __getattr__(name: str):
    if name not in _EXPORTS:
        raise AttributeError(f"module 'campaigns' has no attribute {name!r}")
    return getattr(importlib.import_module(_EXPORTS[name]), name)


def __dir__() -> list[str]:
    """The module's own names and the lazy ones (``dir(campaigns)``, tab completion)."""
    return sorted({*globals(), *_EXPORTS})
