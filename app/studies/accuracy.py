"""The speed-versus-accuracy study behind ``twin accuracy``: runs, stores and charts.

Writes into one directory: ``work_precision.nc`` (+ ``.csv``), ``stability.nc``,
``control_baseline.csv``, and the charts ``work_precision.png/.svg`` and
``stability.png/.svg``. :func:`replot` regenerates the charts from the stored data.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import xarray as xr

from app.studies.charts import campaign_accuracy_chart, stability_chart, work_precision_chart
from app.studies.control_baseline import compare
from app.studies.stability import stability_map
from app.studies.work_precision import STEP_LADDER, TOLERANCE_LADDER, environment, run_study

#: ``--quick``: three steps, one adaptive baseline at one tolerance, one timing, 0.25 s simulated and no
#: stability map: under a minute on an idle 2-core machine (the full study takes many minutes).
QUICK = {"steps": STEP_LADDER[:3], "tolerances": TOLERANCE_LADDER[2:3], "baselines": ("scipy_lsoda",), "repeats": 1}
QUICK_DURATION = 0.25


def run_accuracy(out_dir: str | Path, scene: str = "nominal", duration: float = 1.5, *, quick: bool = False,
                 stability: bool = True, campaign_runs: int = 0, progress=print) -> dict[str, Path]:
    """Run the work-precision study (and the stability map, the python-control baseline and,
    with ``campaign_runs > 0``, the campaign-level comparison) into ``out_dir``.

    ``quick`` trims the step ladder to 1.25e-4 ... 3.1e-5 s and the adaptive baselines to
    ``scipy_lsoda`` at one tolerance, times each run once, simulates at most :data:`QUICK_DURATION` seconds and skips
    the stability map (a first look in under a minute; the full study takes many minutes).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    if quick:
        duration, stability = min(duration, QUICK_DURATION), False
        progress(f"quick study: {QUICK_DURATION} s simulated, steps {', '.join(f'{s:.3g}' for s in QUICK['steps'])} s, "
                 f"{', '.join(QUICK['baselines'])} at rtol {', '.join(f'{t:g}' for t in QUICK['tolerances'])}, "
                 "no stability map; the tight-tolerance reference of each panel is the slowest step")
    study = run_study(scene, duration, progress=progress, **(QUICK if quick else {}))
    study.to_netcdf(out / "work_precision.nc", engine="netcdf4")
    study.to_dataframe().to_csv(out / "work_precision.csv")
    baseline = pd.DataFrame(compare())
    for key, value in environment().items():
        baseline.attrs[key] = value
    baseline.to_csv(out / "control_baseline.csv", index=False)
    progress(baseline.to_string(index=False))
    if stability:
        stability_map(progress=progress).to_netcdf(out / "stability.nc", engine="netcdf4")
    if campaign_runs:
        # lazy: start-up cost (dask and the campaign runner load only when a campaign study runs)
        from campaigns.bench.solver_accuracy import campaign_accuracy

        campaign_accuracy(out / "campaign", runs=campaign_runs)
    return replot(out)


def replot(out_dir: str | Path) -> dict[str, Path]:
    """Regenerate the charts from the stored study data in ``out_dir``."""
    out = Path(out_dir)
    paths = {}
    with xr.open_dataset(out / "work_precision.nc") as study:
        work_precision_chart(study.load(), out / "work_precision.png")
        paths["work_precision"] = out / "work_precision.png"
    if (out / "stability.nc").exists():
        with xr.open_dataset(out / "stability.nc") as data:
            stability_chart(data.load(), out / "stability.png")
            paths["stability"] = out / "stability.png"
    if (out / "campaign" / "campaign_accuracy.nc").exists():
        with xr.open_dataset(out / "campaign" / "campaign_accuracy.nc") as data:
            campaign_accuracy_chart(data.load(), out / "campaign_accuracy.png")
            paths["campaign_accuracy"] = out / "campaign_accuracy.png"
    return paths
