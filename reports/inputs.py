"""Reading and checking the stored files a report is made from.

A report never runs a simulation: it reads ``results.nc`` (written by
:mod:`campaigns.runner.storage`), ``analysis.nc`` (:mod:`campaigns.analysis.campaign_analysis`; computed
in memory from the results when absent) and, optionally, the speed-versus-accuracy
study ``work_precision.nc`` written by ``twin accuracy`` (:mod:`app.studies.work_precision`). Every problem is a
:class:`ReportError` that names the file.
"""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

import xarray as xr

from reports.errors import ReportError

ANALYSIS_NAME = "analysis.nc"
_RESULTS_VARIABLES = ("status", "failure_reason", "wall_time")
_ANALYSIS_VARIABLES = ("n_used", "feature_mean", "feature_std", "spearman", "spearman_ci", "prcc", "overlap",
                       "detection_probability")
#: What the report needs of a work-precision study (``work_precision.nc`` of ``twin accuracy``).
_ACCURACY_VARIABLES = ("wall_time", "feature_error", "status", "method")


@dataclass(frozen=True)
class InputFile:
    """A file the report was made from: its role, name and SHA-256."""

    role: str
    name: str
    sha256: str


@dataclass(frozen=True)
class Inputs:
    """Everything a report shows, loaded into memory.

    Attributes
    ----------
    results : xarray.Dataset
    analysis : xarray.Dataset
    accuracy : xarray.Dataset or None
    spec : dict
        The campaign spec as stored in ``results.attrs["spec_json"]`` (keys ``spec`` and ``resolved``).
    files : tuple of InputFile
    analysis_computed : bool
        True when the analysis was computed in memory (no ``analysis.nc`` found).
    measured : tuple of campaigns.workflows.diagnosis.Diagnosis
        Measured tests placed against this campaign (``twin report --measured``).
    comparison : campaigns.workflows.design_comparison.Comparison or None
        This campaign against another design (``twin report --against``).
    """

    results: xr.Dataset
    analysis: xr.Dataset
    accuracy: xr.Dataset | None
    spec: dict
    files: tuple[InputFile, ...]
    analysis_computed: bool
    measured: tuple = ()
    comparison: object | None = None


def load_inputs(results_path, analysis_path=None, accuracy_path=None, *, measured_paths=(),
                against_path=None) -> Inputs:
    """Open and check the report's input files.

    Parameters
    ----------
    results_path : str or Path
        The campaign's ``results.nc``.
    analysis_path : str or Path, optional
        Its ``analysis.nc``; default: ``analysis.nc`` beside the results if it
        exists, else the analysis is computed in memory (nothing is written).
    accuracy_path : str or Path, optional
        A speed-versus-accuracy study (``work_precision.nc`` of ``twin accuracy``).
    measured_paths : iterable of paths
        Measured tests (``twin measure import``) to place against the campaign (:mod:`campaigns.workflows.diagnosis`).
    against_path : str or Path, optional
        Another design's ``results.nc`` (its ``analysis.nc`` beside it, when there): the report compares this
        campaign against it (:mod:`campaigns.workflows.design_comparison`).

    Raises
    ------
    ReportError
        If a file is missing, unreadable, or lacks what the report needs, or if
        the analysis belongs to another campaign.
    """
    results_path = Path(results_path)
    results = open_netcdf(results_path, "campaign results")
    spec = _check_results(results, results_path)
    files = [_describe("results", results_path)]
    if analysis_path is None and (results_path.parent / ANALYSIS_NAME).is_file():
        analysis_path = results_path.parent / ANALYSIS_NAME
    if analysis_path is None:
        # lazy: start-up cost (scipy and SALib load only when the analysis must be computed here)
        from campaigns.analysis.campaign_analysis import analysis_dataset

        analysis = analysis_dataset(results)
    else:
        analysis_path = Path(analysis_path)
        analysis = open_netcdf(analysis_path, "campaign analysis")
        _check_analysis(analysis, analysis_path, results)
        files.append(_describe("analysis", analysis_path))
    accuracy = None
    if accuracy_path is not None:
        accuracy_path = Path(accuracy_path)
        accuracy = open_netcdf(accuracy_path, "speed-versus-accuracy")
        _check_accuracy(accuracy, accuracy_path)
        files.append(_describe("accuracy", accuracy_path))
    measured = []
    for path in (Path(p) for p in measured_paths):
        test = open_netcdf(path, "measured test")
        if "measured_test" not in test.attrs:
            raise ReportError(path, "not a measured test (no measured_test attribute); make one with "
                                    "`twin measure import`")
        from campaigns.workflows.diagnosis import diagnose  # lazy: only reports with measured tests need it

        try:
            measured.append(diagnose(test, results))
        except ValueError as exc:
            raise ReportError(path, str(exc)) from None
        files.append(_describe("measured test", path))
    comparison = None
    if against_path is not None:
        against_path = Path(against_path)
        other = open_netcdf(against_path, "campaign results")
        _check_results(other, against_path)
        other_analysis = None
        if (against_path.parent / ANALYSIS_NAME).is_file():
            other_analysis = open_netcdf(against_path.parent / ANALYSIS_NAME, "campaign analysis")
            if other_analysis.attrs.get("source_spec_hash") != other.attrs.get("spec_hash"):
                other_analysis = None
        from campaigns.workflows.design_comparison import compare  # lazy: only comparison reports need it

        comparison = compare(other, results, other_analysis, analysis)
        files.append(_describe("compared against", against_path))
    return Inputs(results, analysis, accuracy, spec, tuple(files), analysis_path is None, tuple(measured), comparison)


def open_netcdf(path: Path, what: str) -> xr.Dataset:
    """A netCDF file loaded into memory; a missing, foreign or truncated file is one :class:`ReportError` naming it
    and ``what`` it should have been (``"campaign results"``). Every input of a report is opened here."""
    if not path.exists():
        raise ReportError(path, f"{what} file not found")
    if not path.is_file():
        raise ReportError(path, f"is not a file (expected the {what} netCDF file)")
    try:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            return ds.load()
    except Exception as exc:  # netCDF4/HDF5 raise many types for a truncated or foreign file
        raise ReportError(path, f"cannot be read as a netCDF {what} file ({type(exc).__name__}: {exc}); "
                                "is it complete?") from exc


def _describe(role: str, path: Path) -> InputFile:
    return InputFile(role, path.name, hashlib.sha256(path.read_bytes()).hexdigest())


def _missing(ds: xr.Dataset, names) -> list[str]:
    return [n for n in names if n not in ds.variables]


def _check_results(results: xr.Dataset, path: Path) -> dict:
    problems = [f"variable {n!r} missing" for n in _missing(results, _RESULTS_VARIABLES)]
    problems += [f"dimension {d!r} missing" for d in ("dataset", "run") if d not in results.dims]
    if not any(results[v].attrs.get("role") == "feature" for v in results.data_vars):
        problems.append("no feature variable (attribute role = 'feature')")
    try:
        spec = json.loads(results.attrs["spec_json"])
        spec["spec"]["datasets"]
    except KeyError as exc:
        problems.append(f"spec_json attribute missing or incomplete (no {exc})")
    except (TypeError, json.JSONDecodeError) as exc:
        problems.append(f"spec_json attribute is not valid JSON ({exc})")
    if problems:
        raise ReportError(path, "not a campaign results file: " + "; ".join(problems))
    return spec


def _check_analysis(analysis: xr.Dataset, path: Path, results: xr.Dataset) -> None:
    missing = _missing(analysis, _ANALYSIS_VARIABLES)
    if missing:
        raise ReportError(path, f"not a campaign analysis file: variable(s) {', '.join(missing)} missing")
    stored, expected = analysis.attrs.get("source_spec_hash", ""), results.attrs.get("spec_hash", "")
    if stored and expected and stored != expected:
        raise ReportError(
            path,
            f"analysis of another campaign (spec hash {stored[:16]}, results {expected[:16]}); "
            "re-run `twin campaign analyze` on these results or pass the matching analysis",
        )


def _check_accuracy(accuracy: xr.Dataset, path: Path) -> None:
    missing = _missing(accuracy, _ACCURACY_VARIABLES)
    if missing:
        raise ReportError(path,
                          "not a work-precision study (twin accuracy's work_precision.nc): "
                          f"variable(s) {', '.join(missing)} missing")
    if any(accuracy[v].dims != ("run",) for v in _ACCURACY_VARIABLES):
        raise ReportError(path,
                          f"{', '.join(_ACCURACY_VARIABLES)} must all lie along the dimension 'run' "
                          "(one entry per study run)")
