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

The result is a netCDF file (``twin measure import``) with the mapped signals on the acquisition grid in SI units and
every feature, which :mod:`campaigns.diagnosis` places against a campaign.
"""

from __future__ import annotations

import hashlib
import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pandas as pd
import xarray as xr

from campaigns.units import conversion
from twin.errors import InputError, did_you_mean
from twin.features import FEATURES, MOTION_SPEED_THRESHOLD, N_ACCUMULATORS, accumulate, finish
from twin.layout import SIGNAL_META, Signal

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
            frame = pd.read_csv(path, sep=None, engine="python", comment="#")
            names = [str(c) for c in frame.columns]
            columns = {}
            for n in wanted:
                if n in frame.columns:
                    values = pd.to_numeric(frame[n], errors="coerce").to_numpy(dtype=float)
                    columns[n] = values
    except (OSError, ValueError, pd.errors.ParserError, UnicodeDecodeError) as exc:
        raise MeasuredError(f"measured file {path}", [f"{path}: cannot be read as CSV or netCDF: {exc}"]) from None
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
        if channel.zero == "start":
            held = held - held[0]
        data_vars[signal] = ("time", held, {
            "units": si_unit, "long_name": f"{long_name}, measured on the bench",
            "source_column": channel.column,
            "calibration": f"({channel.gain:g} * raw + {channel.offset:g}) {unit} -> {si_unit}"
                           + ("; zeroed at the procedure's start" if channel.zero == "start" else "")})
    features = measured_features(
        data_vars["linear_encoder_position"][1], data_vars["screw_angle_measured"][1],
        data_vars["torque_measured"][1] if "torque_measured" in data_vars else None, lead=lead, period=period)
    for name, value in features.items():
        declared = FEATURES[name]
        data_vars[name] = ((), value, {"units": declared.unit, "long_name": declared.long_name + " (measured test)",
                                       "description": declared.description, "role": "feature"})
    digest = hashlib.sha256(path.read_bytes()).hexdigest()
    return xr.Dataset(
        data_vars,
        coords={"time": ("time", instants, {"units": "s", "long_name": "acquisition instant from the start of the "
                                                                       "test procedure"})},
        attrs={
            "title": f"Measured test {mapping.name or path.stem}",
            "measured_test": mapping.name or path.stem,
            "source_file": path.name,
            "source_sha256": digest,
            "mapping": mapping.text,
            "scene": mapping.scene or "",
            "parameter_set": params.name,
            "screw_lead": lead,
            "acquisition_period": period,
            "samples": len(instants),
            "resampling": "zero-order hold: the file's last sample at or before each acquisition instant "
                          "(campaigns.measured)",
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
