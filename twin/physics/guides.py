"""Linear guides of the sled: the Abbe error of their angular errors at the linear encoder's reading point.

The sled runs on two profiled rail guides (Sec. 9.2: "The nuts rotation is prevented by two linear bearing guides";
Hiwin RGH20CA, Table B.10) and the linear encoder reads it at a point offset from the screw axis, along which the
nut is driven (Fig. 9.2). A carriage that pitches or yaws as it travels moves that reading point along the axis by
the offset times the change of angle (Abbe's principle: Bryan, "The Abbe principle revisited: an updated
interpretation", Precision Engineering 1, 1979, pp. 129-132). With the angles' change along the travel taken linear
(the lowest-order term of the guides' angular error over the +/-10 mm of a test), pitch ``kappa_p (x - x_0)`` about
the lateral axis and yaw ``kappa_y (x - x_0)`` about the vertical one (x along the screw, y lateral, z up, the
reading point at ``(h_y, h_z)`` from the screw axis), the reading point travels

    x_read - x_read,0 = (x - x_0) + h_z kappa_p (x - x_0) - h_y kappa_y (x - x_0),

a scale-factor error ``1 + h_z kappa_p - h_y kappa_y`` of the reading. Only the measured signals see it: the nut
is on the screw axis.
"""


def abbe_reading_gain(offset_vertical: float, offset_lateral: float, pitch_rate: float, yaw_rate: float) -> float:
    """Travel of the encoder's reading point per metre of sled travel on the screw axis, ``1 + h_z kappa_p -
    h_y kappa_y`` (module docstring).

    Parameters
    ----------
    offset_vertical, offset_lateral : float
        ``h_z``, ``h_y``: the reading point's offsets from the screw axis [m].
    pitch_rate, yaw_rate : float
        ``kappa_p``, ``kappa_y``: change of the sled's pitch and yaw per metre of travel [rad/m].
    """
    return 1.0 + offset_vertical * pitch_rate - offset_lateral * yaw_rate
