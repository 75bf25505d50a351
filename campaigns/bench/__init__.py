"""The bench twin as a campaign model: the one adapter to twin, the bench campaign with its fidelity audit, and the
audits and replays that rerun it."""
