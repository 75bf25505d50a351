"""Measured tests: a test run on the real bench, brought in beside the twin.

A measured file (CSV or netCDF) holds the bench's channels under its own names, units, gains and offsets. A
*mapping* (TOML) says which column is which of the twin's signals (``twin.layout``: ``linear_encoder_position``,
``screw_angle_measured``, ``torque_measured``, ...), in what unit (parsed by pint, :mod:`campaigns.units`) and with
what calibration. :func:`import_measured` reads the file, converts every mapped channel to the twin's SI unit,
resamples it onto the acquisition grid and computes every feature with the twin's own code
(:func:`twin.features.accumulate` and :func:`twin.features.finish`, the functions the compiled loop calls).

How a measured file's samples map to the features' acquisition instants
-----------------------------------------------------------------------
The twin's features are sums over the acquisition instants ``t_k = k T`` (``T`` = the position-loop and acquisition
period, ``controller.position_loop_sample_time``, 1 ms), ``k = 0 ... N`` from the start of the test procedure, of the
readings the acquisition holds at ``t_k`` (the encoders zeroed at ``t = 0``). A measured file is mapped onto them as
the acquisition would have sampled it:

* ``t = 0`` is the start of the procedure: the mapping's ``start`` (in the file's time unit), by default the first
  sample;
* the value at ``t_k`` is the file's last sample at or before ``t_k`` (a zero-order hold, what a sampled-and-held
  reading is; no interpolation, which would invent encoder positions between counts). A file recorded at 1 kHz from
  the procedure's start gives exactly its own samples;
* a file sampled more coarsely than ``T`` is refused (holding a sample for several instants would read the motion as
  stops, which the hysteresis feature leaves out), and so is a gap longer than ``T``;
* position and angle channels are zeroed at ``t = 0`` by default (``zero = "start"``), as the twin's encoders are, so
  a file that records absolute positions gives the same features; torque is not (``zero = "none"``);
* the instants run to the end of the file or, when the mapping names the test's ``scene``, to the end of that
  procedure (a shorter file is refused: its features would be averages over another span).

Before any feature is computed, what a bench cannot produce is refused naming the channel and the likely unit
(:func:`bench_problems`: positions within the 300 mm stroke of Table 9.3, the sled and the screw-equivalent position
agreeing within the backlash, the torque within the torque meter's range): a wrong unit would otherwise give a
confident wrong diagnosis. A CSV file is read in chunks, its mapped columns only (:func:`_read_csv`).

The result is a netCDF file (``twin measure import``) with the mapped signals on the acquisition grid in SI units and
every feature, which :mod:`campaigns.workflows.diagnosis` places against a campaign.
"""

from __future__ import annotations

import csv
import hashlib
import math
import tomllib
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
import pandas as pd
import xarray as xr

from campaigns.units import conversion, quantity
from twin.errors import InputError, did_you_mean
from twin.features import FEATURES, MOTION_SPEED_THRESHOLD, N_ACCUMULATORS, accumulate, finish
from twin.layout import SIGNAL_META, Signal
from twin.scenes.procedure import STROKE
from twin.scenes.profiles import profile_values

#: Signals a measured test may map, with their SI unit and long name (the twin's names, ``twin.layout``).
SIGNALS = {signal.name.lower(): SIGNAL_META[signal] for signal in Signal}
#: The channels the features are made of (:mod:`twin.features`): sled position, screw angle, torque.
FEATURE_CHANNELS = ("linear_encoder_position", "screw_angle_measured", "torque_measured")
#: Features computed from a measured test: the measured ones (no true signals exist on a real bench).
MEASURED_FEATURES = tuple(name for name in FEATURES if not name.endswith("_true"))
#: A sample spacing this much above the acquisition period still counts as on it (time stamps in text files).
SPACING_TOLERANCE = 0.01
#: Mapping fields.
TEST_FIELDS = ("name", "scene", "parameters", "time", "time_unit", "start")
CHANNEL_FIELDS = ("column", "unit", "gain", "offset", "zero")
#: The largest backlash a scene may state (``twin.scenes.CONDITIONS["backlash"]``: 0 ... 1 mm) [m].
LARGEST_BACKLASH = 1e-3
#: How far the sled position may move from the screw-equivalent position over a test (both zeroed at the start) [m]:
#: the backlash (at most LARGEST_BACKLASH) plus the drive chain's elastic deflection at the 12 kN of Table 9.3 (the
#: thrust bearing's 400 N/µm of Table B.9 alone gives 30 µm; shaft and nut contacts a few times that), the lead error
#: (7.3e-5 of the 300 mm stroke, 22 µm) and the encoders' errors (µm). Twice the largest backlash covers them all; a
#: wrong unit (a factor 1000, 57 or 10 between the two channels) exceeds it on any motion longer than a few mm.
ALLOWED_DISAGREEMENT = 2 * LARGEST_BACKLASH
#: Common units of a signal's dimension, for the "is the unit µm?" hint of a reading out of a bench's range.
COMMON_UNITS = {"m": ("m", "cm", "mm", "µm", "nm", "in"), "rad": ("rad", "mrad", "deg", "arcmin", "arcsec", "turn"),
                "N m": ("N m", "N cm", "N mm", "mN m", "kN m")}
#: Rows of a CSV file read at a time (a 10 s test at 1 kHz is 10 001 rows; long logs are read in chunks of this).
CSV_CHUNK_ROWS = 100_000
#: Delimiters a CSV file may use (a spreadsheet's export: comma; semicolon where the comma is the decimal sign).
CSV_DELIMITERS = ",;\t|"
#: Bytes read to tell the delimiter and the header.
CSV_SAMPLE_BYTES = 64 * 1024


class MeasuredError(InputError):
    """A measured file or its mapping cannot be used; ``problems`` names each field or channel at fault."""

    def __init__(self, what: str, problems: list[str]):
        super().__init__(what, problems)


@dataclass(frozen=True)
class Channel:
    """One mapped channel: ``si = conversion(unit) (gain * raw + offset)``, zeroed at the start or not."""

    signal: str
    column: str
    unit: str | None = None
    gain: float = 1.0
    offset: float = 0.0
    zero: str = "start"


@dataclass(frozen=True)
class Mapping:
    """A measured file's mapping onto the twin's signals (the TOML of ``--mapping``)."""

    channels: dict[str, Channel]
    name: str = ""
    scene: str | None = None
    parameters: str = "bench"
    time: str = "time"
    time_unit: str = "s"
    start: float | None = None
    text: str = field(default="", repr=False)


def _default_zero(signal: str) -> str:
    unit = SIGNALS[signal][0]
    return "start" if unit in ("m", "rad") and ("measured" in signal or "encoder" in signal) else "none"


def load_mapping(path: str | Path) -> Mapping:
    """Read and check a mapping file; every problem is listed at once (:class:`MeasuredError`).

    Format::

        [test]
        name = "bench run 2026-11-20"   # optional
        scene = "ds2"                   # the procedure the bench ran (optional: sets the span and is recorded)
        parameters = "bench"            # parameter set of the screw lead (default bench)
        time = "Time"                   # the time column (CSV) or variable (netCDF)
        time_unit = "ms"                # default s
        start = 0.0                     # file time at which the procedure starts (default: the first sample)

        [channels.linear_encoder_position]   # a twin signal name
        column = "LinEnc_X"                   # the file's column / variable
        unit = "mm"                           # pint unit of the calibrated value (netCDF: default its units)
        gain = 1.0                            # calibrated = gain * raw + offset, in `unit`
        offset = 0.0
        zero = "start"                        # or "none" (default: start for encoder positions and angles)
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
        data = tomllib.loads(text)
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise MeasuredError(f"mapping {path}", [f"{path}: cannot read the mapping: {exc}"]) from None
    problems = []
    for key in data:
        if key not in ("test", "channels"):
            hint = did_you_mean(key, ("test", "channels"))
            problems.append(f"{key}: unknown table; {hint + ' ' if hint else ''}allowed: test, channels")
    test = data.get("test", {})
    if not isinstance(test, dict):
        problems.append("test: must be a table")
        test = {}
    for key in test:
        if key not in TEST_FIELDS:
            hint = did_you_mean(key, TEST_FIELDS)
            problems.append(f"test.{key}: unknown field; {hint + ' ' if hint else ''}allowed: {', '.join(TEST_FIELDS)}")
    channels = {}
    table = data.get("channels", {})
    if not isinstance(table, dict) or not table:
        problems.append("channels: give at least one [channels.<signal>] table "
                        f"(the features need {', '.join(FEATURE_CHANNELS)})")
        table = {}
    for signal, entry in table.items():
        where = f"channels.{signal}"
        if signal not in SIGNALS:
            hint = did_you_mean(signal, SIGNALS)
            measured = ", ".join(s for s in SIGNALS if s.endswith("_measured") or "encoder" in s)
            problems.append(f"{where}: not a signal of the twin; {hint + ' ' if hint else ''}"
                            f"measured signals: {measured}")
            continue
        if not isinstance(entry, dict):
            problems.append(f"{where}: must be a table with column, unit, gain, offset")
            continue
        for key in entry:
            if key not in CHANNEL_FIELDS:
                hint = did_you_mean(key, CHANNEL_FIELDS)
                problems.append(f"{where}.{key}: unknown field; {hint + ' ' if hint else ''}"
                                f"allowed: {', '.join(CHANNEL_FIELDS)}")
        if not isinstance(entry.get("column"), str) or not entry.get("column"):
            problems.append(f"{where}.column: required, the file's column or variable name")
        for key in ("gain", "offset"):
            value = entry.get(key, 1.0 if key == "gain" else 0.0)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
                problems.append(f"{where}.{key}: must be a finite number, got {value!r}")
        if entry.get("gain") == 0:
            problems.append(f"{where}.gain: must not be 0")
        zero = entry.get("zero", _default_zero(signal))
        if zero not in ("start", "none"):
            problems.append(f"{where}.zero: must be 'start' or 'none', got {zero!r}")
        unit = entry.get("unit")
        if unit is not None:
            try:
                conversion(str(unit), SIGNALS[signal][0])
            except ValueError as exc:
                problems.append(f"{where}.unit: {exc}")
        if not any(p.startswith(where) for p in problems):
            channels[signal] = Channel(signal, entry["column"], unit, float(entry.get("gain", 1.0)),
                                       float(entry.get("offset", 0.0)), zero)
    try:
        conversion(str(test.get("time_unit", "s")), "s")
    except ValueError as exc:
        problems.append(f"test.time_unit: {exc}")
    start = test.get("start")
    if start is not None and (isinstance(start, bool) or not isinstance(start, (int, float))
                              or not math.isfinite(start)):
        problems.append(f"test.start: must be a finite number (in time_unit), got {start!r}")
    for key in ("name", "scene", "parameters", "time"):
        if key in test and not isinstance(test[key], str):
            problems.append(f"test.{key}: must be a string, got {test[key]!r}")
    if problems:
        raise MeasuredError(f"mapping {path}", problems)
    return Mapping(channels, name=test.get("name", ""), scene=test.get("scene"),
                   parameters=test.get("parameters", "bench"), time=test.get("time", "time"),
                   time_unit=str(test.get("time_unit", "s")), start=None if start is None else float(start), text=text)


def _read_columns(path: Path, mapping: Mapping) -> tuple[dict[str, np.ndarray], dict[str, str]]:
    """The mapped columns and the time as float arrays, and each column's own ``units`` (netCDF only)."""
    wanted = [mapping.time, *(c.column for c in mapping.channels.values())]
    units: dict[str, str] = {}
    try:
        if path.suffix.lower() in (".nc", ".nc4", ".cdf", ".netcdf"):
            with xr.open_dataset(path, decode_times=False) as ds:
                names = list(ds.variables)
                columns = {n: np.asarray(ds[n].values, dtype=float) for n in wanted if n in ds.variables}
                units = {n: str(ds[n].attrs["units"]) for n in wanted if n in ds.variables and "units" in ds[n].attrs}
        else:
            names, columns = _read_csv(path, wanted)
    except (OSError, ValueError, pd.errors.ParserError, UnicodeDecodeError) as exc:
        if isinstance(exc, MeasuredError):
            raise
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise MeasuredError(f"measured file {path}", [f"{path}: cannot be read as CSV or netCDF: {first}"]) from None
    problems = []
    for n in dict.fromkeys(wanted):
        if n not in columns:
            hint = did_you_mean(n, names, cutoff=0.6)
            problems.append(f"{path.name}: no column {n!r}; {hint + ' ' if hint else ''}columns: {', '.join(names)}")
        elif columns[n].ndim != 1:
            problems.append(f"{path.name}: {n!r} is not one series (shape {columns[n].shape})")
        elif not np.isfinite(columns[n]).all():
            bad = int((~np.isfinite(columns[n])).sum())
            problems.append(f"{path.name}: {n!r} has {bad} sample(s) that are empty, not numbers or not finite")
    if problems:
        raise MeasuredError(f"measured file {path}", problems)
    return columns, units


def _csv_layout(path: Path) -> tuple[str, list[str]]:
    """The delimiter and the column names of a CSV file, from its first lines (``#`` lines are comments; a UTF-8 byte
    order mark, as Excel's "CSV UTF-8" writes, is dropped)."""
    with path.open(encoding="utf-8-sig", newline="") as handle:
        sample = handle.read(CSV_SAMPLE_BYTES)
    lines = sample.splitlines()
    if len(sample) == CSV_SAMPLE_BYTES:
        lines = lines[:-1]  # the last line may be cut
    lines = [line for line in lines if line.strip() and not line.lstrip().startswith("#")]
    if not lines:
        raise MeasuredError(f"measured file {path}", [
            f"{path.name}: the file is empty (no header line naming the columns, no samples)"])
    try:
        delimiter = csv.Sniffer().sniff("\n".join(lines[:50]), delimiters=CSV_DELIMITERS).delimiter
    except csv.Error:  # a single column, or rows the sniffer cannot tell apart: the CSV default
        delimiter = ","
    return delimiter, [name.strip() for name in next(csv.reader([lines[0]], delimiter=delimiter))]


def _read_csv(path: Path, wanted: list[str]) -> tuple[list[str], dict[str, np.ndarray]]:
    """The column names of a CSV file and its wanted columns (those it has) as float arrays: read in chunks of
    CSV_CHUNK_ROWS rows and only the wanted columns kept, so the memory is that of the float arrays, not of the text
    (benchmarks/measured_import_memory.py). A sample that is not a number becomes NaN (reported by the caller); a
    column whose numbers have a comma as the decimal sign is refused, naming it (one line for them all)."""
    delimiter, names = _csv_layout(path)
    present = [n for n in dict.fromkeys(wanted) if n in names]
    if not present:
        return names, {}
    parts: dict[str, list[np.ndarray]] = {n: [] for n in present}
    comma_decimals: dict[str, str] = {}
    chunks = pd.read_csv(path, sep=delimiter, encoding="utf-8-sig", comment="#",
                         usecols=lambda column: str(column).strip() in present,
                         skipinitialspace=True, chunksize=CSV_CHUNK_ROWS)
    with chunks:
        for chunk in chunks:
            chunk.columns = [str(c).strip() for c in chunk.columns]
            for n in present:
                column = chunk[n]
                if not pd.api.types.is_numeric_dtype(column):
                    text = column.dropna().astype(str).str.strip()
                    comma = text[text.str.fullmatch(r"[-+]?\d*,\d+([eE][-+]?\d+)?")]
                    if len(comma) and n not in comma_decimals:
                        comma_decimals[n] = comma.iloc[0]
                    column = pd.to_numeric(column, errors="coerce")
                parts[n].append(column.to_numpy(dtype=float))
    if comma_decimals:
        named = ", ".join(f"{n!r} ({example!r})" for n, example in comma_decimals.items())
        raise MeasuredError(f"measured file {path}", [
            f"{path.name}: column(s) {named} write numbers with a comma as the decimal sign; save the file with a "
            "point as the decimal sign (a spreadsheet's CSV export in an English locale)"])
    return names, {n: np.concatenate(chunk) if chunk else np.empty(0) for n, chunk in parts.items()}


def acquisition_grid(time: np.ndarray, period: float, start: float, end: float | None) -> tuple[np.ndarray, np.ndarray]:
    """The acquisition instants ``t_k = k period`` from ``start`` (relative times) and, for each, the index of the
    file's last sample at or before it (a zero-order hold). ``end`` (relative) caps the span; by default it is the
    file's last sample."""
    span = (time[-1] - start) if end is None else end
    count = int(math.floor(span / period + 1e-9)) + 1
    instants = np.arange(count) * period
    # a time stamp written with a few digits may fall a hair after its instant: 1e-6 T of slack
    index = np.searchsorted(time, start + instants + 1e-6 * period, side="right") - 1
    return instants, index


def torque_limit(params) -> float:
    """The largest torque the bench's torque meter reads [N m]: the nominal torque of its larger range (Table B.5),
    where its ±10 V output and the ±10 V acquisition end."""
    return max(params.value("sensors.torque_meter_full_scale_range1"),
               params.value("sensors.torque_meter_full_scale_range2"))


def unit_hint(signal: str, channel: Channel, factor: float) -> str:
    """``is the unit µm rather than 'mm'?`` when readings ``factor`` times what they should be are what a common unit
    of the signal's dimension read as the channel's unit gives; else a word to check the unit and gain."""
    si_unit = SIGNALS[signal][0]
    scale = conversion(channel.unit, si_unit)[0]
    if math.isfinite(factor) and factor > 0:
        for candidate in COMMON_UNITS.get(si_unit, ()):
            if abs(math.log(factor * conversion(candidate, si_unit)[0] / scale)) < math.log(1.2):
                return f"is the unit {candidate} rather than {channel.unit!r}?"
    return f"check its unit ({channel.unit}) and gain ({channel.gain:g})"


def _times(factor: float) -> str:
    return f"{factor:.0f}×" if factor >= 100 else f"{factor:.2g}×"


def bench_problems(calibrated: dict[str, np.ndarray], channels: dict[str, Channel], *, lead: float,
                   torque_limit: float, demand: np.ndarray | None = None) -> list[str]:
    """What a bench cannot have produced, each naming the channel and the likely cause (a wrong unit or gain).

    ``calibrated``: each mapped signal in SI at the acquisition instants (before zeroing); ``channels``: their
    mapping, with the unit used (the file's own for a netCDF variable the mapping gives none); ``demand``: the scene's
    position demand there, when the mapping names the scene. Checked: the sled position and the screw-equivalent
    position (``lead / 2 pi`` times the screw angle) each span at most the bench's stroke (Table 9.3,
    ``twin.scenes.procedure.STROKE``); they agree, both zeroed at the start, within ALLOWED_DISAGREEMENT (the
    backlash and the chain's deflection), which bounds the backlash features too (means and differences of means of
    that disagreement); the torque reads within the torque meter's range. Of two positions that disagree, the one
    farther from the demand's span is named (both, without a scene)."""
    sled = calibrated["linear_encoder_position"]
    screw = lead / (2.0 * math.pi) * calibrated["screw_angle_measured"]
    what = {"linear_encoder_position": "the sled position",
            "screw_angle_measured": "the screw-equivalent position (lead / 2π × screw_angle_measured)"}
    spans = {"linear_encoder_position": float(np.ptp(sled)), "screw_angle_measured": float(np.ptp(screw))}
    problems = []
    for signal, span in spans.items():
        other = next(s for s in spans if s != signal)
        if span > STROKE:
            factor = span / spans[other] if spans[other] > 0 else math.nan
            problems.append(
                f"channels.{signal}: {what[signal]} spans {quantity(span, 'm', 4)}, more than the bench's "
                f"{quantity(STROKE, 'm')} stroke (Table 9.3)"
                + (f"; values {_times(factor)} {what[other]} ({quantity(spans[other], 'm', 4)})"
                   if math.isfinite(factor) else "")
                + f": {unit_hint(signal, channels[signal], factor)}")
    gap = float(np.max(np.abs((sled - sled[0]) - (screw - screw[0]))))
    if not problems and gap > ALLOWED_DISAGREEMENT:
        ratio = spans["linear_encoder_position"] / spans["screw_angle_measured"] if spans["screw_angle_measured"] \
            else math.inf
        suspects = list(spans)
        if demand is not None and np.ptp(demand) > 0:
            reference = float(np.ptp(demand))
            suspects = [max(spans, key=lambda s: abs(math.log(max(spans[s], 1e-300) / reference)))]
        hints = {s: unit_hint(s, channels[s], ratio if s == "linear_encoder_position" else 1.0 / ratio)
                 for s in suspects}
        hint = next(iter(hints.values())) if len(hints) == 1 else "; or ".join(f"{s}: {h}" for s, h in hints.items())
        problems.append(
            f"channels.{suspects[0]}: {what['linear_encoder_position']} spans "
            f"{quantity(spans['linear_encoder_position'], 'm', 4)} and {what['screw_angle_measured']} "
            f"{quantity(spans['screw_angle_measured'], 'm', 4)}; they part by up to {quantity(gap, 'm', 3)}, more "
            f"than a bench's backlash and deflection allow ({quantity(ALLOWED_DISAGREEMENT, 'm')})"
            + (f" (the scene's demand spans {quantity(float(np.ptp(demand)), 'm', 4)})" if demand is not None else "")
            + f"; {hint}")
    if "torque_measured" in calibrated:
        peak = float(np.max(np.abs(calibrated["torque_measured"])))
        if peak > torque_limit:
            problems.append(f"channels.torque_measured: readings up to {quantity(peak, 'N m', 4)}, beyond the "
                            f"torque meter's {quantity(torque_limit, 'N m')} full scale (Table B.5): "
                            f"{unit_hint('torque_measured', channels['torque_measured'], math.nan)}")
    return problems


def measured_features(sled: np.ndarray, screw_angle: np.ndarray, torque: np.ndarray | None, *, lead: float,
                      period: float) -> dict[str, float]:
    """Every feature of :data:`twin.features.FEATURES` (measured ones) from the readings at the acquisition instants,
    by the twin's own accumulate/finish: ``d_k = x_k - (lead / 2 pi) theta_k``, the motion threshold
    ``MOTION_SPEED_THRESHOLD * period``. Without a torque channel the torque feature is NaN."""
    acc = np.zeros(N_ACCUMULATORS)
    arm = lead / (2.0 * math.pi)
    threshold = MOTION_SPEED_THRESHOLD * period
    torque_values = np.zeros_like(sled) if torque is None else torque
    for k in range(len(sled)):
        accumulate(acc, float(sled[k]), arm * float(screw_angle[k]), float(torque_values[k]), k == 0, threshold)
    values = finish(acc, float(len(sled)))
    if torque is None:
        values["drag_torque_feature"] = math.nan
    return values


def import_measured(path: str | Path, mapping: Mapping | str | Path) -> xr.Dataset:
    """Read a measured test, map and calibrate its channels, resample them onto the acquisition grid and compute
    every feature with the twin's code (module docstring).

    Returns
    -------
    xarray.Dataset
        ``time`` (the acquisition instants from the procedure's start [s]), one variable per mapped signal in its SI
        unit, the features as scalars (``role = "feature"``), and attributes naming the file (with its SHA-256), the
        mapping, the scene and the lead used.

    Raises
    ------
    MeasuredError
        Naming the file, the column or the mapping field at fault, before anything is computed.
    """
    import twin  # lazy: the parameter set and the scene (the features' code is imported above)

    path = Path(path)
    if not isinstance(mapping, Mapping):
        mapping = load_mapping(mapping)
    missing = [c for c in FEATURE_CHANNELS[:2] if c not in mapping.channels]
    if missing:
        raise MeasuredError(f"mapping for {path.name}", [
            f"channels.{c}: required; the backlash features are made of the linear encoder and the torque-meter "
            "encoder (Eq. 9.12)" for c in missing])
    if not path.is_file():
        raise MeasuredError(f"measured file {path}", [f"{path}: no such file"])
    params = twin.load_parameters(mapping.parameters)
    period = params.value("controller.position_loop_sample_time")
    lead = params.value("ball_screw.lead")
    scene = twin.load_scene(mapping.scene) if mapping.scene else None
    columns, units = _read_columns(path, mapping)
    scale, offset = conversion(mapping.time_unit, "s")
    time = columns[mapping.time] * scale + offset
    problems = []
    if len(time) == 0:
        raise MeasuredError(f"measured file {path}", [f"{path.name}: no samples under the header line"])
    if len(time) < 2 or not (np.diff(time) > 0).all():
        problems.append(f"{path.name}: the time column {mapping.time!r} must increase from sample to sample")
    if problems:
        raise MeasuredError(f"measured file {path}", problems)
    start = time[0] if mapping.start is None else mapping.start * scale + offset
    spacing = float(np.max(np.diff(time[time >= start - 1e-9]))) if (time >= start).sum() > 1 else math.inf
    if spacing > period * (1.0 + SPACING_TOLERANCE):
        problems.append(f"{path.name}: samples up to {spacing * 1e3:.4g} ms apart, coarser than the "
                        f"{period * 1e3:g} ms acquisition period the features are defined on; record at least at the "
                        "acquisition rate")
    if not time[0] <= start <= time[-1]:
        problems.append(f"test.start: {start:g} s is outside the file's time span {time[0]:g} ... {time[-1]:g} s")
    end = None
    if scene is not None and not problems:
        covered = time[-1] - start
        if covered < scene.duration - 1e-6 * period:
            problems.append(f"{path.name}: covers {covered:.6g} s of the {scene.duration:g} s procedure of scene "
                            f"{scene.name}; its features would be averages over another span")
        end = scene.duration
    if problems:
        raise MeasuredError(f"measured file {path}", problems)
    instants, index = acquisition_grid(time, period, start, end)
    data_vars = {}
    calibrated: dict[str, np.ndarray] = {}
    used: dict[str, Channel] = {}
    for signal, channel in mapping.channels.items():
        si_unit, long_name = SIGNALS[signal]
        unit = channel.unit or units.get(channel.column)
        if unit is None:
            raise MeasuredError(f"mapping for {path.name}", [
                f"channels.{signal}.unit: required for a CSV column (the file states no unit for {channel.column!r})"])
        try:
            c_scale, c_offset = conversion(unit, si_unit)
        except ValueError as exc:
            raise MeasuredError(f"mapping for {path.name}", [f"channels.{signal}.unit: {exc}"]) from None
        values = (channel.gain * columns[channel.column] + channel.offset) * c_scale + c_offset
        held = values[index]
        calibrated[signal], used[signal] = held, replace(channel, unit=unit)
        if channel.zero == "start":
            held = held - held[0]
        data_vars[signal] = ("time", held, {
            "units": si_unit, "long_name": f"{long_name}, measured on the bench",
            "source_column": channel.column,
            "calibration": f"({channel.gain:g} * raw + {channel.offset:g}) {unit} -> {si_unit}"
                           + ("; zeroed at the procedure's start" if channel.zero == "start" else "")})
    problems = bench_problems(calibrated, used, lead=lead, torque_limit=torque_limit(params),
                              demand=None if scene is None else profile_values(scene.position_table(), instants))
    if problems:
        raise MeasuredError(f"measured file {path}", problems)
    features = measured_features(
        data_vars["linear_encoder_position"][1], data_vars["screw_angle_measured"][1],
        data_vars["torque_measured"][1] if "torque_measured" in data_vars else None, lead=lead, period=period)
    for name, value in features.items():
        declared = FEATURES[name]
        data_vars[name] = ((), value, {"units": declared.unit, "long_name": declared.long_name + " (measured test)",
                                       "description": declared.description, "role": "feature"})
    with path.open("rb") as handle:  # streamed: a long log is not held twice
        digest = hashlib.file_digest(handle, "sha256")
    return xr.Dataset(
        data_vars,
        coords={"time": ("time", instants, {"units": "s", "long_name": "acquisition instant from the start of the "
                                                                       "test procedure"})},
        attrs={
            "title": f"Measured test {mapping.name or path.stem}",
            "measured_test": mapping.name or path.stem,
            "source_file": path.name,
            "source_sha256": digest.hexdigest(),
            "mapping": mapping.text,
            "scene": mapping.scene or "",
            "parameter_set": params.name,
            "screw_lead": lead,
            "acquisition_period": period,
            "samples": len(instants),
            "resampling": "zero-order hold: the file's last sample at or before each acquisition instant "
                          "(campaigns.workflows.measured)",
            "features": "twin.features.accumulate/finish over the acquisition instants, as in the twin's loop",
        },
    )


def read_measured(path: str | Path) -> xr.Dataset:
    """A measured test written by ``twin measure import`` (loaded; times in seconds)."""
    path = Path(path)
    try:
        with xr.open_dataset(path, decode_times=False) as ds:
            ds = ds.load()
    except (OSError, ValueError) as exc:
        first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
        raise MeasuredError(f"measured test {path}", [
            f"{path}: cannot be read as a netCDF file ({first}); a measured test is the file `twin measure import` "
            "writes from the bench's CSV or netCDF"]) from None
    if "measured_test" not in ds.attrs:
        raise MeasuredError(f"measured test {path}", [
            f"{path}: not a measured test (no measured_test attribute); make one with `twin measure import`"])
    return ds
