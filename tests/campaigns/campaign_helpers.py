"""Helpers of the campaign tests: the synthetic test spec and its variants."""

from __future__ import annotations

from pathlib import Path

import xarray as xr

import campaigns
from campaigns.runner.synthetic import SYNTHETIC_CATALOG

DATA = Path(__file__).parent / "data"
SYNTHETIC_SPEC = DATA / "synthetic.toml"


def write_spec(tmp_path: Path, text: str, *, append: bool = False) -> Path:
    """Write a variant of the synthetic test spec.

    ``text`` holds overrides (the file ``extends`` the synthetic spec), or with
    ``append`` more TOML after its content (to add rows to its lists).
    """
    path = tmp_path / "spec.toml"
    path.write_text(SYNTHETIC_SPEC.read_text() + text if append else f'extends = "{SYNTHETIC_SPEC}"\n{text}')
    return path


def load(path: Path, **kwargs) -> campaigns.CampaignSpec:
    """``load_spec`` with the synthetic model's catalog."""
    return campaigns.load_spec(path, catalog=SYNTHETIC_CATALOG, **kwargs)


def data_variables(ds: xr.Dataset) -> xr.Dataset:
    """The variables that must not depend on workers or chunking (wall_time measures the machine)."""
    return ds.drop_vars("wall_time").drop_attrs()
