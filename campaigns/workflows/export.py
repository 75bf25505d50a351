"""A campaign's numbers for the people a review circulates to: tidy tables in CSV, Excel or MATLAB files.

:func:`tables` turns ``results.nc`` (and ``analysis.nc`` when given) into tidy tables, one observation per row and one
variable per column, every column with its unit in the header (``backlash_feature [m]``, ``[1]`` for a ratio):

``runs``
    one row per run: data set, run (with unit and repeat in a within-unit campaign), status, failure reason, the
    data set's conditions, every sampled parameter, every feature, the loop margins, the integrator, ``t_reached``
    and the wall time;
``features`` (analysis)
    per data set and feature: runs used and excluded, whether the data suffice, mean and standard deviation;
``sensitivity`` (analysis)
    per data set, feature and parameter: Spearman and Pearson with their bootstrap intervals, PRCC, the first-order
    index with its interval and flag, the effect size with its interval;
``detection`` (analysis)
    per feature, data set and reference data set: detection probability and overlap coefficient;
``verdicts`` (analysis)
    per feature: the requirement verdict and its statement, the minimum detectable fault size's bounds and bracket;
``design_limits`` (analysis of bench campaigns)
    per loop and design limit: the verdict, the runs beyond it, the fraction with its interval, the statement.

:func:`export` writes them: ``csv`` (one file per table), ``xlsx`` (one workbook, one sheet per table, through
pandas and openpyxl) or ``mat`` (one MATLAB file with a struct per table, through ``scipy.io.savemat``: MATLAB field
names cannot hold units or dots, so each struct also holds ``columns``, the headers with their units, in field
order).
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pandas as pd
import xarray as xr

from campaigns.runner.files import CampaignError, atomic_write

FORMATS = ("csv", "xlsx", "mat")


def _header(name: str, units: str | None) -> str:
    return f"{name} [{units}]" if units not in (None, "") else name


def _units(da: xr.DataArray) -> str | None:
    units = da.attrs.get("units")
    return None if units is None else str(units)


def runs_table(results: xr.Dataset) -> pd.DataFrame:
    """One row per run (module docstring)."""
    names = [str(d) for d in results["dataset"].values]
    runs = results["run"].values
    columns: dict[str, np.ndarray] = {
        "dataset": np.repeat(names, len(runs)),
        "run": np.tile(runs, len(names)),
    }
    for name in ("unit", "repeat"):  # a within-unit campaign: which unit, which of its tests
        if name in results.coords:
            columns[name] = np.tile(results[name].values, len(names))
    by_role = {role: [str(v) for v in results.data_vars if results[v].attrs.get("role") == role]
               for role in ("sampled", "feature", "margin")}
    for name in ("status", "failure_reason"):
        if name in results:
            columns[name] = results[name].transpose("dataset", "run").values.astype(str).ravel()
    for name in (str(v) for v in results.data_vars if str(v).startswith("condition_")):
        if results[name].dims == ("dataset",):
            columns[_header(name.removeprefix("condition_"), _units(results[name]))] = np.repeat(
                results[name].values, len(runs))
    for name in by_role["sampled"] + by_role["feature"] + by_role["margin"]:
        columns[_header(name, _units(results[name]))] = results[name].transpose("dataset", "run").values.ravel()
    for name in ("integrator", "t_reached", "wall_time"):
        if name in results and results[name].dims == ("dataset", "run"):
            values = results[name].transpose("dataset", "run").values.ravel()
            columns[_header(name, _units(results[name]))] = values.astype(str) if values.dtype.kind in "OUS" else values
    return pd.DataFrame(columns)


def _long(analysis: xr.Dataset, variables: list[str], dims: tuple[str, ...]) -> pd.DataFrame:
    """The variables along ``dims`` as one tidy table; a ``bound`` axis becomes ``_lower``/``_upper`` columns."""
    frame = None
    for name in variables:
        if name not in analysis:
            continue
        da = analysis[name]
        # a statistic of features in several units says so in a comment
        # (campaigns.analysis.campaign_analysis._feature_units)
        units = _units(da) if "units" in da.attrs else (
            "feature units" if "feature_units" in str(da.attrs.get("comment", "")) else None)
        parts = ([(f"{name}_{b}", da.sel(bound=b)) for b in ("lower", "upper")] if "bound" in da.dims
                 else [(name, da)])
        for column, part in parts:
            series = part.transpose(*dims).to_series().rename(_header(column, units))
            frame = series.to_frame() if frame is None else frame.join(series)
    if frame is None:
        return pd.DataFrame()
    frame = frame.reset_index()
    if "feature" in dims and "feature_units" in analysis.coords:
        units = dict(zip(analysis["feature"].values.astype(str), analysis["feature_units"].values.astype(str),
                         strict=True))
        frame.insert(list(frame.columns).index("feature") + 1, "feature units", frame["feature"].map(units))
    return frame


def analysis_tables(analysis: xr.Dataset) -> dict[str, pd.DataFrame]:
    """The analysis tables (module docstring)."""
    out = {
        "features": _long(analysis, ["n_used", "n_excluded", "data_sufficient", "feature_mean", "feature_std"],
                          ("dataset", "feature")),
        "sensitivity": _long(analysis, ["spearman", "spearman_ci", "pearson", "pearson_ci", "prcc",
                                        "first_order_index", "first_order_index_ci", "first_order_index_flag",
                                        "effect_size", "effect_size_ci"], ("dataset", "feature", "parameter")),
        "detection": _long(analysis, ["detection_probability", "overlap"], ("feature", "dataset", "reference")),
    }
    verdict = [v for v in analysis.data_vars if analysis[v].dims in (("feature",), ("feature", "bound"))]
    out["verdicts"] = _long(analysis, [v for v in ("requirement_verdict", "requirement_statement") if v in verdict]
                            + sorted(v for v in verdict if v.startswith("minimum_detectable")), ("feature",))
    if "margin_limit_verdict" in analysis:
        frame = _long(analysis, ["margin_limit_verdict", "margin_limit_fraction", "margin_limit_fraction_ci",
                                 "margin_limit_statement"], ("limit_check",))
        counts = analysis["margin_limit_counts"].values
        frame.insert(2, "runs beyond the limit", counts[:, 0])
        frame.insert(3, "runs with the margin", counts[:, 1])
        out["design_limits"] = frame
    for frame in out.values():
        for column in frame.columns:
            if frame[column].dtype == object:
                frame[column] = frame[column].astype(str)
    return out


def tables(results: xr.Dataset, analysis: xr.Dataset | None = None) -> dict[str, pd.DataFrame]:
    """Every table of a campaign: ``runs`` and, with an analysis, the analysis tables."""
    out = {"runs": runs_table(results)}
    if analysis is not None:
        out.update(analysis_tables(analysis))
    return out


def file_names(fmt: str, table_names) -> list[str]:
    """The files :func:`export` writes for ``fmt`` (checked against the write rule before anything is written)."""
    if fmt == "csv":
        return [f"{name}.csv" for name in table_names]
    return [f"campaign.{fmt}"]


def _matlab_name(header: str, taken: set[str]) -> str:
    """A MATLAB field name for a column header: letters, digits, underscores, a letter first, at most 63 chars."""
    name = re.sub(r"\s*\[.*\]$", "", header)
    name = re.sub(r"[^0-9A-Za-z_]", "_", name).strip("_") or "column"
    name = ("x" + name if not name[0].isalpha() else name)[:63]
    base, k = name, 2
    while name in taken:
        name = f"{base[:60]}_{k}"
        k += 1
    taken.add(name)
    return name


def export(frames: dict[str, pd.DataFrame], fmt: str, out_dir: Path, *, campaign: str = "") -> list[Path]:
    """Write the tables in ``fmt`` into ``out_dir`` (created); returns the files written.

    Each file is written to a temporary file beside it and moved onto its name when complete
    (:func:`campaigns.runner.files.atomic_write`): a full disk or a refused directory leaves every earlier file as it
    was (an earlier export is not destroyed by a ``--force`` one that fails), never a truncated table under its name.

    Raises
    ------
    CampaignError
        Naming the directory or the file that could not be written, and the files already written before it.
    """
    if fmt not in FORMATS:
        raise ValueError(f"unknown format {fmt!r}; one of {', '.join(FORMATS)}")
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CampaignError(f"cannot create the directory {out_dir}: {exc.strerror or exc}; choose another --out") \
            from exc
    if fmt == "csv":
        writers = {out_dir / f"{name}.csv": (lambda tmp, frame=frame: frame.to_csv(tmp, index=False))
                   for name, frame in frames.items()}
    elif fmt == "xlsx":
        writers = {out_dir / "campaign.xlsx": lambda tmp: _write_xlsx(frames, tmp)}
    else:
        writers = {out_dir / "campaign.mat": lambda tmp: _write_mat(frames, tmp, campaign)}
    written: list[Path] = []
    for path, write in writers.items():
        try:
            atomic_write(path, write)
        except CampaignError as exc:
            if written:
                raise CampaignError(f"{exc} (written before it: {', '.join(p.name for p in written)})") from exc
            raise
        written.append(path)
    return written


def _write_xlsx(frames: dict[str, pd.DataFrame], path: Path) -> None:
    with pd.ExcelWriter(path, engine="openpyxl") as writer:
        for name, frame in frames.items():
            frame.to_excel(writer, sheet_name=name[:31], index=False)


def _write_mat(frames: dict[str, pd.DataFrame], path: Path, campaign: str) -> None:
    from scipy.io import savemat  # lazy: only the MATLAB export needs scipy.io

    content = {"campaign": campaign}
    for name, frame in frames.items():
        taken: set[str] = set()
        struct = {}
        headers = []
        for column in frame.columns:
            field = _matlab_name(str(column), taken)
            values = frame[column].to_numpy()
            struct[field] = values.astype(object) if values.dtype.kind in "OUS" else values.astype(float)
            headers.append(str(column))
        struct["columns"] = np.array(headers, dtype=object)
        content[name] = struct
    # appendmat=False: the temporary file's name is not to get ".mat" appended
    savemat(path, content, appendmat=False, long_field_names=True, do_compression=True, oned_as="column")
