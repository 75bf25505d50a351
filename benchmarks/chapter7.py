"""The chapter 7 validation (docs/validation.md, "Validation of the free nut against the thesis's Chapter 7"):
the Sec. 7.9.3 scenes run, their figures and ``chapter7.nc`` written into --out, and the numbers the page quotes
printed, with the wall time.

    python benchmarks/chapter7.py --out out/chapter7          # the three scenes and Fig. 7.19 (about 10 s compiled)
    python benchmarks/chapter7.py --out out/chapter7 --quick  # chapter7_backlash and Fig. 7.19 only
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np
from machine import header

from app.studies.chapter7 import SCENES, run_chapter7

#: The per-reversal measurements printed, with their unit and display scale.
PRINTED = {"reversal_time": ("s", 1.0), "stop_duration": ("ms", 1e3), "screw_travel_while_stopped": ("um", 1e6),
           "force_free_duration": ("ms", 1e3), "peak_support_friction": ("N", 1.0),
           "peak_ball_groove_torque": ("mN m", 1e3)}
#: Forces at which Fig. 7.19's deflection past the flank is printed [N].
FORCES = (100.0, 500.0, 1000.0, 2000.0, 4000.0)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=Path("out/chapter7"))
    parser.add_argument("--quick", action="store_true", help="only chapter7_backlash and Fig. 7.19")
    args = parser.parse_args()
    header("Chapter 7 validation: the free nut at the reversals (Sec. 7.9.3) and Fig. 7.19", args.quick)
    start = time.perf_counter()
    out = run_chapter7(args.out, scenes=SCENES[:1] if args.quick else SCENES)
    print(f"# wall {time.perf_counter() - start:.1f} s (with the first run's compilation if the cache was cold)")
    for scene in SCENES[:1] if args.quick else SCENES:
        print(f"{scene}: backlash {float(out[f'{scene}_backlash']) * 1e6:g} um, loop width (t <= 0.25 s) "
              f"{float(out[f'{scene}_loop_width']) * 1e6:.1f} um")
        for name, (unit, scale) in PRINTED.items():
            print(f"  {name} [{unit}]: {np.round(out[f'{scene}_{name}'].values * scale, 3).tolist()}")
        if f"{scene}_loop_width_loaded" in out:
            print(f"  loop width under the external force: {float(out[f'{scene}_loop_width_loaded']) * 1e6:.1f} um")
    past = out.displacement.values - 0.5 * out.attrs["backlash"]
    closed = past > 0
    for law in ("variable_angle", "design_angle"):
        deflections = np.interp(FORCES, out[f"force_{law}"].values[closed], past[closed]) * 1e6
        print(f"Fig. 7.19, {law}: deflection past the flank at {', '.join(f'{f:g}' for f in FORCES)} N: "
              f"{', '.join(f'{d:.2f}' for d in deflections)} um")
    worst = np.max(np.abs(out.force_variable_angle.values[closed] / out.closed_form_variable_angle.values[closed] - 1))
    print(f"Fig. 7.19: run-time law against Hertz evaluated directly: largest relative difference {worst:.1e}")
    print("figures: " + ", ".join(out.attrs["figures"]))


if __name__ == "__main__":
    main()
