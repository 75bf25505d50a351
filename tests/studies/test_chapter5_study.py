"""The Ch. 5 validation study (`twin chapter5`): it writes its figures and its numbers are the model's."""

import json

import pytest

from app.cli import main


def test_chapter5_study_writes_the_figures_and_the_trends_of_chapter5(tmp_path, capsys):
    """Steady-state part only (no simulation): every figure is written; the numbers behave as Secs. 5.3-5.4
    describe (zero efficiency without load, a peak past the transition 2 F_pr, a monotone fall with k_rf) and the
    drag torque sits on Eq. 7.85 at its 1 kN calibration point."""
    assert main(["chapter5", "--out", str(tmp_path), "--no-dynamic"]) == 0
    names = {p.name for p in tmp_path.glob("*.png")}
    assert names == {"fig5_6_efficiency_vs_force.png", "fig5_7_efficiency_vs_preload.png",
                     "fig5_8_efficiency_vs_krf.png", "fig5_10_efficiency_map.png", "fig7_22_drag_torque.png",
                     "fig5_13_regimes.png"}
    data = json.loads((tmp_path / "chapter5.json").read_text())
    assert set(data) == {"efficiency", "drag", "regimes"}
    out = capsys.readouterr().out
    assert "efficiency_at_zero_load: 0.0" in out
    krf = data["efficiency"]["vs_k_rf"]["500"]
    assert all(a > b for a, b in zip(krf, krf[1:], strict=False))
    drag = dict(zip(data["drag"]["preloads"], data["drag"]["model_100"], strict=True))
    catalogue = dict(zip(data["drag"]["preloads"], data["drag"]["catalogue"], strict=True))
    assert drag[1000.0] == pytest.approx(catalogue[1000.0], rel=0.02)
