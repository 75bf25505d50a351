"""Section "Fidelity": the automatic fidelity levels and their audit against the full model."""

from __future__ import annotations

import re
from collections import Counter

from reports.builder import Builder
from reports.model import Callout, Paragraph
from reports.phrases import statement_tone

#: The integrator a spec's JSON carries when nothing else is asked for (campaigns.runner.spec), spelled here because a
#: report reads results files and never imports the twin. What solved each run is what the run recorded
#: (results.nc ``integrator``).
DEFAULT_INTEGRATOR = "rk4"

#: One feature's part of a ``fidelity_audit_<data set>`` attribute (campaigns.bench.fidelity_audit.summary_attrs; the
#: features are separated by " | "): its verdict statement, shown verbatim, then the descriptive figures, each with
#: the display unit of the feature's unit (µm for a length, mN·m for a torque).
_AUDIT_LINE = re.compile(r"^(?P<feature>\w+): (?P<statement>(met|not met|undetermined|insufficient data): .+); "
                         r"max paired (?P<paired>(?:[-+0-9.e]+|nan) \S+), MC error (?P<error>(?:[-+0-9.e]+|nan) \S+), "
                         r"KS p (?P<p>[-+0-9.e]+|nan)$")
#: The start of the statement of a data set the audit did not re-run (campaigns.bench.fidelity_audit.IDENTICAL).
_IDENTICAL = "met: identical:"


def _figure(text: str) -> str:
    """An audit figure as stored (four decimals and its unit); a missing one as an en dash."""
    return "–" if text.startswith("nan") or not text else text


def build(b: Builder):
    attrs = {k: str(v) for k, v in b.results.attrs.items() if k.startswith("fidelity")}
    if not attrs:
        yield Callout("No fidelity configuration or audit is recorded in results.nc (no attribute named fidelity*).")
        return
    requested = attrs.pop("fidelity_requested", "").strip('"') or "–"
    audit = attrs.pop("fidelity_audit", "not recorded")
    runs = attrs.pop("fidelity_audit_runs", None)
    yield Paragraph(
        f"The campaign asked for fidelity '{requested}': with 'auto' each subsystem of the twin runs at the cheapest "
        "level the scene and its outputs allow (twin/fidelity/rules.toml), where that level measurably pays: a scene "
        "whose stored speedup of the automatic levels is below the rules' min_lane_speedup runs the full model "
        "(twin/fidelity/speed.toml), and a fault sweep runs one set of levels, its most detailed member's. A data "
        "set whose every run took the full model's levels is not re-run: its audit pairs would be identical bit for "
        "bit, and it is marked \"met: identical: the automatic choice is the full model\". The audit re-runs the "
        "first " + (f"{runs} " if runs and runs != "0" else "")
        + "runs of each data set the automatic choice simplifies at full fidelity with the same parameters and noise "
        "(the audit's budget, fidelity_audit.runs per data set of the campaign, shared among those data sets) and "
        "judges each feature by the paired part of the accuracy rule (docs/accuracy.md): met when the 95 % "
        "Student-t interval of the mean shift (automatic minus full) lies within the tolerance of the feature's unit "
        "(±0.05 µm for a length, 5 % of the 1 µm backlash requirement; ±1.43 mN·m for a torque, 5 % of the "
        "drag-torque change of the 200 N preload-loss requirement) and the 95 % interval of the ratio of standard "
        "deviations within 1 ± 10 %, not met when either interval lies wholly outside, undetermined otherwise, "
        "insufficient data below 5 paired runs. At a campaign's audit runs this is a screen; the rule accepts a "
        "default from "
        "200 paired runs per data set. The scene's numerical floor (the spread of tight runs that differ only in "
        "their step or by picometres of backlash) is shown beside each verdict as context."
    )
    yield Callout(f"Audit result: {audit}.", statement_tone(audit))
    configured = [(d, attrs.pop(f"fidelity_{d}")) for d in b.datasets if f"fidelity_{d}" in attrs]
    if configured:
        yield b.table("Subsystem levels the automatic choice used, per data set (subsystem = level).",
                      ("Data set", "Subsystem levels"), [(d, level.replace("=", " = ")) for d, level in configured])
    yield from _integrators(b)
    rows, speedups = [], []
    for d in b.datasets:
        text = attrs.pop(f"fidelity_audit_{d}", None)
        if text is None:
            continue
        if text.startswith(_IDENTICAL):  # not re-run: one row for every feature
            rows.append((d, "every feature", text, "–", "–", "–", "–"))
            continue
        speedup = re.search(r"speedup x([-+0-9.e]+|nan)", text)
        lines = [_AUDIT_LINE.match(part) for part in re.sub(r"^speedup x\S+; ", "", text).split(" | ")]
        if not all(lines):  # a format this report does not know (an older audit): shown as stored
            rows.append((d, "–", text.replace(" um", " µm"), "", "", "", ""))
            continue
        for k, m in enumerate(lines):
            shown_speedup = f"{float(speedup.group(1)):.2f}" if speedup and k == 0 else ""
            if speedup and k == 0:
                speedups.append(float(speedup.group(1)))
            rows.append((d, m["feature"], m["statement"], _figure(m["paired"]), _figure(m["error"]), m["p"],
                         shown_speedup))
    if rows:
        yield b.table(
            "Automatic against full fidelity on the same runs: the verdict on the paired mean shift of the feature "
            "as the audit stated it, the largest paired difference, the Monte Carlo error of the mean (1.96 σ/√N), "
            "the KS p-value (descriptive only), and speedup = full-fidelity wall time / automatic wall time over the "
            "paired runs.",
            ("Data set", "Feature", "Verdict", "Largest paired difference", "Monte Carlo error", "KS p", "Speedup"),
            rows,
        )
    if speedups:  # no re-run data set: no speedup measured, nothing to say about it
        slower = [x for x in speedups if x < 1]
        yield Paragraph(
            "Speedup above 1: the automatic choice ran faster than full fidelity. "
            + (f"Here {len(slower)} of {len(speedups)} data sets show a speedup below 1, i.e. the automatic runs took "
               "longer. The audit times the first runs of each data set, which on freshly started workers include "
               "loading the compiled model, and wall time depends on the machine's load; it says nothing about "
               "accuracy, which the verdict column judges." if slower else
               "Wall time depends on the machine's load and on the first runs' start-up; it says nothing about "
               "accuracy.")
        )
    if attrs:
        yield b.table("Other fidelity attributes recorded in results.nc.", ("Attribute", "Value"),
                      [(k, v.replace(" um", " µm")) for k, v in attrs.items()])


def _step_in_micro(label: str) -> str:
    """A solver label as results.nc stores it (twin.simulation.solver_label, ASCII "rk4 at 62.5 us"), in the report's
    unit spelling ("rk4 at 62.5 µs")."""
    return re.sub(r"(\d) us$", r"\1 µs", label)


def _integrators(b: Builder):
    """The method and step that solved each run, counted per data set (results.nc ``integrator``)."""
    requested = (b.spec.get("solver") or {}).get("integrator", DEFAULT_INTEGRATOR)
    rows = []
    for d in b.datasets if "integrator" in b.results else ():
        counts = Counter(str(v) for v in b.results["integrator"].sel(dataset=d).values.ravel())
        unrecorded = counts.pop("", 0)  # runs that failed before solving, or chunks written before the variable
        if counts:
            rows.append((d, ", ".join([*(f"{_step_in_micro(method)}: {n}" for method, n in sorted(counts.items())),
                                       *([f"not recorded: {unrecorded}"] if unrecorded else [])])))
    if not rows:
        yield Paragraph(f"The campaign asked for integrator '{requested}'; which method solved each run is not "
                        "recorded in this results.nc (written before the runs recorded it, or by a run function that "
                        "does not report it).")
        return
    yield Paragraph(f"The campaign asked for integrator '{requested}'. The table counts the method and step that "
                    "solved each run.")
    yield b.table("Integrator that solved the runs, per data set (method and step: runs).", ("Data set", "Integrator"),
                  rows)
