"""The settings every statistic of a campaign defaults to: one confidence for every interval and bound, and the
detection rule's false-alarm rate and power (docs/campaigns.md, Analysis)."""

#: Detection settings of the verdict: the threshold flags this fraction of the reference's runs ...
FALSE_ALARM_RATE = 0.05
#: ... and the minimum detectable level is where this fraction of a data set's runs is flagged.
POWER = 0.95
#: Confidence of the bootstrap bounds and of the order-statistic floor.
CONFIDENCE = 0.95
