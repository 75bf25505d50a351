"""Torque meter reading (BURSTER 8661-5050, Table B.5; Sec. 9.3 "Torque meter").

The torque is streamed from rotor to stator with a 1000 Hz refresh, "therefore
some instantaneous torque peaks may be lost during the acquisition" (Sec. 9.3):
the output is a sample-and-hold of the true torque at the refresh instants,
converted by the meter's 16-bit D/A to ±10 V over the selected range (50 or
5 N*m). Sensitivity tolerance and the temperature effects on zero (%FS/K) and
on sensitivity (%Nom/K) follow Table 9.5, driven by room temperature - 25 °C.

The compiled functions are the generic channel's (:mod:`sensors.analog`, lane
form): ``analog_init(state, p, l, T0, t0)``, ``analog_step(state, p, l, T, t)``
at every integration step and ``analog_read(state, p, l, noise)`` at sample
instants, with ``p`` the lanes' vectors from :func:`torque_meter_parameters`
completed by :func:`sensors.analog.with_integration_step`. The torque meter's angle
comes from its encoder (:func:`sensors.encoder.torque_meter_encoder_parameters`).

Table 9.5 lists the range-I temperature effects as ±0.01 %FS/K on offset and
±0.015 %Nom/K on sensitivity, Table B.5 the other way round (and likewise for
range II); the twin follows Table 9.5, the uncertainty model of the thesis's
Monte Carlo analysis (see ``docs/sensors.md``).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

from sensors.analog import select_range, sensor_channel
from sensors.parameters import sensor_values


def torque_meter_parameters(params: Mapping[str, float], *, room_temperature: float) -> np.ndarray:
    """Analog channel parameters of the torque meter on its selected range.

    Parameters
    ----------
    params : mapping
        Validated parameter values, the whole ``sensors`` group (:func:`sensors.parameters.sensor_values`).
    room_temperature : float
        Room temperature of the test [K] (scene condition ``room_temperature``).

    Returns
    -------
    numpy.ndarray
        Layout ``AN_*`` of :mod:`sensors.analog`.
    """
    v = sensor_values(params)
    r = select_range(v, "sensors.torque_meter_range")
    return sensor_channel(
        v,
        room_temperature=room_temperature,
        full_scale=v[f"sensors.torque_meter_full_scale_range{r}"],
        output_full_scale=v["sensors.torque_meter_output_full_scale"],
        sensitivity_errors=[v[f"sensors.torque_meter_sensitivity_error_range{r}"]],
        sensitivity_tempcos=[v[f"sensors.torque_meter_sensitivity_tempco_range{r}"]],
        offsets=[],
        offset_tempcos=[v[f"sensors.torque_meter_offset_tempco_range{r}"]],
        refresh_period=1.0 / v["sensors.torque_meter_refresh_rate"],
        output_bits=v["sensors.torque_meter_dac_bits"],
    )
