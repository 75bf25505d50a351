"""Estimators and decision rules on sampled runs: sensitivity indices, the paired comparison, the accuracy rule."""
