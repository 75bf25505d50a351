"""Analyses of a campaign's results: correlations, separation, observability, within-unit detection, model form,
control robustness."""
