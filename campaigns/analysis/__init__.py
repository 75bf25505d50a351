"""Analyses of a campaign's results, each (results, settings) -> xarray.Dataset, and the composer that writes
analysis.nc: feature statistics, correlations, separation, observability, within-unit detection, control robustness,
model form."""
