"""The Monte Carlo runner: a spec, its sampled runs, their execution on dask, their storage and provenance."""
