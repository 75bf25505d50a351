"""One campaign from spec to report: what ``twin campaign run --analyze --report`` and ``twin serve`` both run.

The sequence lives here, above ``campaigns`` and ``reports`` (the layers forbid ``campaigns`` from
importing ``reports``), so that the CLI and the service cannot drift apart: both call
:func:`run_campaign_pipeline` and differ only in how they show its progress.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import campaigns
from campaigns.runner.spec import CampaignSpec


@dataclass
class PipelineOutputs:
    """The files a pipeline wrote (``analysis`` is ``None`` without analysis; ``reports`` empty without report)."""

    results: Path
    analysis: Path | None = None
    reports: dict[str, Path] = field(default_factory=dict)


def run_campaign_pipeline(
    spec: CampaignSpec,
    out: Path,
    *,
    analyze: bool = True,
    report: bool = True,
    workers: int = 2,
    scheduler: str | None = None,
    resume: bool = False,
    allow_version_mix: bool = False,
    progress: bool = True,
    announce: Callable[[str, str], None] | None = None,
    wrote: Callable[[str, Path], None] | None = None,
) -> PipelineOutputs:
    """Run (or resume) a campaign, then analyse it and build its report.

    Parameters
    ----------
    spec : CampaignSpec
        The validated spec.
    out : Path
        Output directory (``results.nc``, ``analysis.nc``, ``report.html``, ``report.pdf``).
    analyze, report : bool
        Also write ``analysis.nc`` / ``report.html`` and ``report.pdf``.
    workers, scheduler, resume, allow_version_mix, progress
        As :func:`campaigns.run_campaign`.
    announce : callable, optional
        ``announce(stage, message)`` as each stage starts (the run stages of
        :func:`campaigns.run_campaign`, then ``analysis`` and ``report``).
    wrote : callable, optional
        ``wrote(kind, path)`` as each output is written: kind ``results``, ``analysis``, ``html``, ``pdf``.

    Returns
    -------
    PipelineOutputs
    """
    announce = announce or (lambda stage, message: None)
    wrote = wrote or (lambda kind, path: None)
    outputs = PipelineOutputs(campaigns.run_campaign(spec, out, workers=workers, scheduler=scheduler, resume=resume,
                                                     allow_version_mix=allow_version_mix, progress=progress,
                                                     announce=announce))
    wrote("results", outputs.results)
    if analyze:
        announce("analysis", "correlations with bootstrap intervals, separation, observability")
        outputs.analysis = campaigns.analyze(outputs.results)
        wrote("analysis", outputs.analysis)
    if report:
        from reports import build_report  # lazy: figures and typst cost start-up time; only reports need them

        announce("report", "figures, HTML and PDF")
        outputs.reports = build_report(outputs.results, out_dir=out)
        for kind, path in outputs.reports.items():
            wrote(kind, path)
    return outputs
