"""The bench twin as a campaign model: the one adapter to twin, and the audits and replays that rerun it."""
