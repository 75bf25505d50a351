"""Section "Feature distributions": each feature's spread per data set."""

from __future__ import annotations

from reports import figures
from reports.builder import ROUND_OFF, Builder
from reports.figures import MAX_TRACES
from reports.model import Paragraph
from reports.units import quantity


def build(b: Builder):
    yield Paragraph(
        "Probability density of each feature over the successful runs of every data set: a histogram with a Gaussian "
        "kernel density estimate (Figs. 9.8 and 9.10 of the thesis). The measured feature (from the bench's sensors) "
        "is drawn beside the true-signal feature (from the model's states): their difference is what the "
        f"instrumentation adds. With more than {MAX_TRACES} data sets each gets its own row on a shared axis. "
        "Failed runs are left out."
    )
    for feature in b.measured:
        stacked = len(b.datasets) > MAX_TRACES
        yield b.figure(
            f"distribution-{feature}",
            f"{b.label(feature)}: "
            + ("measured (left) and from the true signals (right), " if b.true_of(feature) else "")
            + ("one row per data set, each row scaled to its own peak. " if stacked else "all data sets. ")
            + "Look at how far apart the data sets with and without backlash lie compared with the width of each "
            "distribution, and at the shift caused by preload or external force. Data sets: "
            + "; ".join(b.describe(d) for d in b.datasets) + ".",
            figures.distributions(b.distribution_panels(feature, b.datasets)),
        )
    rows, muted = [], []
    for name in b.datasets:
        for feature in b.features:
            f = b.analysis.sel(dataset=name, feature=feature)
            mean, std, unit = (float(f["feature_mean"]), float(f["feature_std"]),
                               b.results[feature].attrs.get("units", ""))
            # a spread at round-off level is a constant feature, not a measurement of scatter
            spread = "0 (constant)" if std <= ROUND_OFF * abs(mean) else quantity(std, unit)
            reason = b.insufficient(name, feature)
            rows.append((name, feature, str(int(f["n_used"])), quantity(mean, unit), spread, reason or "–"))
            muted.append(reason is not None)
    yield b.table("Mean and standard deviation of each feature over the runs used (status ok, finite feature); greyed "
                  "rows rest on too few runs.",
                  ("Data set", "Feature", "Runs used", "Mean", "Standard deviation", "Data"), rows, muted)
