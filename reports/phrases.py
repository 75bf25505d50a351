"""The words every part of a report shares: verdicts and their decisions, the tone each is shown in, features and
parameters in words, "insufficient data", the hint to re-run the analysis.

One home for each phrase, so page 1, the sections and the procedure-search report say a verdict the same way. Numbers
and units in words are :mod:`reports.units`'s; a section's own sentences stay in its module.
"""

from __future__ import annotations

#: Tone of each requirement verdict (CONTRACT.md: the analysis writes exactly one of these).
VERDICT_TONES = {"met": "good", "not met": "bad", "undetermined": "info", "insufficient data": "muted"}
#: Leading words of the fidelity audit in results written before its three-way verdict (issue 16).
_LEGACY_AUDIT_TONES = {"passed": "good", "FLAGGED": "bad"}
#: The decision words of each verdict.
DECISIONS = {"met": "GO", "not met": "NO-GO", "undetermined": "UNDETERMINED", "insufficient data": "NO DATA"}
#: The verdict of statistics resting on too few runs (one of the analysis's verdicts, and the report's word for it).
INSUFFICIENT = "insufficient data"
#: Features in words (a feature not listed is named by its stored long name).
FEATURE_WORDS = {
    "backlash_feature": "the backlash feature f_b (Eq. 9.12)",
    "backlash_hysteresis": "the backlash hysteresis",
    "drag_torque_feature": "the drag torque",
}
#: The command that writes what an older analysis.nc lacks.
REANALYZE = "re-run `twin campaign analyze`"
#: What page 1 and the Observability section say when the analysis predates the requirement verdict.
NO_VERDICT = ("Requirement verdict: not available. This analysis.nc holds no requirement_verdict / "
              f"requirement_statement (written by an older analysis); {REANALYZE} on the results to obtain the "
              "verdict with its bounds and sample size.")


def tone(verdict: str) -> str:
    """The tone a verdict is shown in (``"info"`` for a word that is no verdict)."""
    return VERDICT_TONES.get(verdict, "info")


def decision(verdict: str) -> str:
    """``GO``, ``NO-GO``, ``UNDETERMINED`` or ``NO DATA``; any other word in capitals."""
    return DECISIONS.get(verdict, verdict.upper())


def statement_tone(statement: str) -> str:
    """The tone of a stored statement from the verdict it starts with (``"not met: ..."``); ``"info"`` if none."""
    head = statement.split(":", 1)[0].split(" (", 1)[0]
    return VERDICT_TONES.get(head, _LEGACY_AUDIT_TONES.get(head, "info"))


def insufficient(n: int, minimum: int) -> str:
    """``insufficient data: 7 ok run(s) < 10``: why a data set's statistics are withheld."""
    return f"{INSUFFICIENT}: {n} ok run(s) < {minimum}"


def feature_words(results, feature: str) -> str:
    """A feature in page 1's words, else its stored long name (else its name)."""
    return FEATURE_WORDS.get(feature, str(results[feature].attrs.get("long_name", feature)))


def plain_name(parameter: str) -> str:
    """``sensors.linear_encoder_phase_asymmetry`` -> ``linear encoder phase asymmetry (sensors)``."""
    group, _, key = parameter.rpartition(".")
    words = key.replace("_", " ")
    return f"{words} ({group})" if group else words
