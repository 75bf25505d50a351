"""Which seal friction law holds the free nut: the body the seal carries on a free-nut data set, shaken by the force
loop's hunting, under the regularised law (three v_th) and the LuGre and elasto-plastic laws (issue 41, item 2).

The body: the piston and the master nut pinned to it (pneumatics.piston_mass + sled.master_mass), on the seal's
friction (pneumatics.toml: F_s, F_d, a, b, and the bristle parameters), under a force ``F_0 + A sin(2 pi f t)``
below breakaway: the external force's hunting on ds2-ds7 while the screw is at rest is 56-129 N of standard
deviation (docs/accuracy.md). Printed per law: the mean speed over the last second (the drift), the RMS speed, and
the travel, after 1 s of settling; RK4 at 10 us (app.studies.friction_laws), 3 s. No model run: seconds of CPU.

    python benchmarks/friction_laws.py
"""

from __future__ import annotations

import numpy as np
from machine import header

import twin
from app.studies import friction_laws as fl

DT, DURATION, SETTLE = 1.0e-5, 3.0, 1.0
CASES = [(0.0, 100.0, 10.0), (20.0, 100.0, 10.0), (20.0, 200.0, 10.0), (20.0, 200.0, 30.0)]  # F_0 [N], A [N], f [Hz]


def main() -> None:
    header("seal friction laws under the force loop's hunting (a body on the law, no model run)")
    v = twin.load_parameters().value
    p = "pneumatics."
    mass = v(p + "piston_mass") + v("sled.master_mass")
    laws = [("regularised, v_th 5 mm/s", fl.REGULARISED, 5.0e-3), ("regularised, v_th 1 mm/s", fl.REGULARISED, 1.0e-3),
            ("regularised, v_th 0.25 mm/s", fl.REGULARISED, 2.5e-4), ("LuGre", fl.LUGRE, 0.0),
            ("elasto-plastic", fl.ELASTOPLASTIC, 0.0)]
    print(f"# body {mass:g} kg; F_s {v(p + 'friction_static'):g} N, F_d {v(p + 'friction_dynamic'):g} N; sigma_0 "
          f"{v(p + 'friction_presliding_stiffness'):g} N/m, z_ba "
          f"{v(p + 'friction_elastic_fraction') * v(p + 'friction_dynamic'):g} N of bristle force")
    print("| force [N] | law | drift [um/s] | RMS speed [mm/s] | travel after settling [um] |")
    print("|---|---|---|---|---|")
    for force0, amplitude, frequency in CASES:
        for name, law, v_th in laws:
            params = fl.law_parameters(
                mass, v(p + "friction_static"), v(p + "friction_dynamic"), v(p + "friction_stribeck_coefficient"),
                v(p + "friction_presliding_stiffness"), v(p + "friction_bristle_damping"),
                v(p + "friction_bristle_damping_speed"), v(p + "friction_viscous"),
                v(p + "friction_elastic_fraction") * v(p + "friction_dynamic") / v(p + "friction_presliding_stiffness"),
                v_th)
            t, y = fl.integrate(law, params, DURATION, DT, fl.drive(0.0, 0.0, force0, amplitude, frequency, 0.0))
            late = t >= SETTLE
            last = t >= DURATION - 1.0
            drift = (y[-1, 0] - y[last][0, 0]) / 1.0
            print(f"| {force0:g} + {amplitude:g} sin(2 pi {frequency:g} t) | {name} | {drift * 1e6:.3g} | "
                  f"{np.sqrt(np.mean(y[late, 1] ** 2)) * 1e3:.3g} | {(y[-1, 0] - y[late][0, 0]) * 1e6:.3g} |")


if __name__ == "__main__":
    main()
