"""Estimators and decision rules on sampled runs: order statistics, intervals, correlations, detection, sensitivity
indices, the paired comparison, the accuracy rule, and the default confidence and detection settings."""
