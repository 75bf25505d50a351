"""Studies built on the simulation engine: work-precision, stability limits."""
