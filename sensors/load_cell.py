"""Force readings: external-force load cell and preload load cell + conditioner.

External force: HBM K-U9C 20 kN load cell (Table B.13) with its conditioner:
a first-order low-pass at its 3.8 kHz -3 dB cut-off followed by a sample-and-hold
at its 19.2 kHz measuring rate, mapped to ±10 V over ±20 kN. Table 9.5 "Load cell" rows: repeatability
(%Read), offset (%FS), sensitivity (%Nom) and their temperature effects.
Repeatability is a per-test scatter proportional to the reading, so within one
run it acts as an extra gain error.

Preload: Lorenz K-1882 toroidal load cell, 1/10 kN ranges (Table B.7), and
LCV/U10 conditioner (Table B.8: ±10 V, first-order 10 kHz cut-off, exact
discretisation in :func:`sensors.acquisition.first_order_lag`). Table 9.5
"Preload load cell" rows: accuracy (%Nom, an additive error bounded by that
fraction of the range's nominal force), sensitivity and temperature effects per
range; "Preload load cell conditioning module" rows: temperature effects,
which add to the cell's.

Table 9.5's external load-cell ranges differ from Table B.13's datasheet
figures (e.g. sensitivity ±0.1 %Nom vs ±1 %/±2 %); the twin follows Table 9.5,
the uncertainty model of the thesis's Monte Carlo analysis (docs/sensors.md).

The compiled functions are the generic channel's (:mod:`sensors.analog`, lane
form): ``analog_init``, ``analog_step`` (every integration step) and
``analog_read`` (sample instants), with the builders' vectors completed by
:func:`sensors.analog.with_integration_step`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

import numpy as np

from sensors.analog import select_range, sensor_channel
from sensors.parameters import sensor_values


def load_cell_parameters(params: Mapping[str, float], *, room_temperature: float) -> np.ndarray:
    """Analog channel parameters of the external-force load cell (Table B.13).

    Parameters
    ----------
    params : mapping
        Validated parameter values, the whole ``sensors`` group (:func:`sensors.parameters.sensor_values`).
    room_temperature : float
        Room temperature of the test [K].
    """
    v = sensor_values(params)
    return sensor_channel(
        v,
        room_temperature=room_temperature,
        full_scale=v["sensors.load_cell_nominal_force"],
        output_full_scale=v["sensors.load_cell_output_full_scale"],
        sensitivity_errors=[v["sensors.load_cell_sensitivity_error"], v["sensors.load_cell_repeatability_error"]],
        sensitivity_tempcos=[v["sensors.load_cell_sensitivity_tempco"]],
        offsets=[v["sensors.load_cell_offset"]],
        offset_tempcos=[v["sensors.load_cell_offset_tempco"]],
        tau=1.0 / (2.0 * math.pi * v["sensors.load_cell_conditioner_cutoff_frequency"]),
        refresh_period=1.0 / v["sensors.load_cell_measuring_rate"],
    )


def preload_load_cell_parameters(params: Mapping[str, float], *, room_temperature: float) -> np.ndarray:
    """Analog channel parameters of the preload load cell + conditioner on the selected range.

    Parameters
    ----------
    params : mapping
        Validated parameter values, the whole ``sensors`` group (:func:`sensors.parameters.sensor_values`).
    room_temperature : float
        Room temperature of the test [K].
    """
    v = sensor_values(params)
    r = select_range(v, "sensors.preload_load_cell_range")
    return sensor_channel(
        v,
        room_temperature=room_temperature,
        full_scale=v[f"sensors.preload_load_cell_nominal_force_range{r}"],
        output_full_scale=v["sensors.preload_conditioner_output_full_scale"],
        sensitivity_errors=[v[f"sensors.preload_load_cell_sensitivity_error_range{r}"]],
        sensitivity_tempcos=[
            v[f"sensors.preload_load_cell_sensitivity_tempco_range{r}"],
            v[f"sensors.preload_conditioner_sensitivity_tempco_range{r}"],
        ],
        offsets=[v["sensors.preload_load_cell_accuracy_error"]],
        offset_tempcos=[
            v[f"sensors.preload_load_cell_offset_tempco_range{r}"],
            v["sensors.preload_conditioner_offset_tempco"],
        ],
        tau=1.0 / (2.0 * math.pi * v["sensors.preload_conditioner_cutoff_frequency"]),
    )
