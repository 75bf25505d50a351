"""The overview plot of one run (twin.plotting, ``twin simulate --plot``): panel (b) shows the Eq. 9.12 feature as it
accumulates and ends on the run's feature; the hysteresis loop of nut minus screw by the screw's direction of motion
fills the sixth slot, its two branch means the run's hysteresis width apart (issue 39)."""

import numpy as np
import pytest

import twin
from twin.plotting import plot_run


@pytest.fixture(scope="module")
def ds2_plot():
    import matplotlib.pyplot as plt

    # without the winding temperature (ds2 runs the full model, twin/fidelity/speed.toml): six panels
    ds = twin.simulate(twin.load_scene("ds2").with_duration(1.5), fidelity={"motor_thermal": "frozen"})
    fig = plot_run(ds)
    yield ds, fig
    plt.close(fig)


def _panel(fig, letter: str):
    return next(ax for ax in fig.axes if ax.get_visible() and ax.get_title().startswith(f"({letter})"))


def test_panel_b_is_the_feature_as_it_accumulates_and_ends_on_the_runs_feature(ds2_plot):
    """The running mean of |d| over the recorded samples: at the default output spacing (the 1 ms acquisition
    period) these are the samples Eq. 9.12 averages, so its last value is the run's feature up to the rounding of
    the same sum taken in another order (1e-9 relative: the sum of 1500 terms of ~40 um rounds at ~1e-13)."""
    ds, fig = ds2_plot
    ax = _panel(fig, "b")
    assert "Eq. 9.12" in ax.get_title() and "accumulates" in ax.get_title()
    ends = {line.get_label(): line.get_ydata()[-1] for line in ax.get_lines()}
    true = next(value for label, value in ends.items() if label.startswith("running mean, true"))
    encoders = next(value for label, value in ends.items() if label.startswith("running mean, encoders"))
    assert true == pytest.approx(float(ds.backlash_feature_true) * 1e6, rel=1e-9)
    assert encoders == pytest.approx(float(ds.backlash_feature) * 1e6, rel=1e-9)


def test_the_sixth_slot_is_the_hysteresis_loop_whose_branches_are_the_hysteresis_width_apart(ds2_plot):
    """The two branch means of the loop differ by the run's ``backlash_hysteresis_true`` (the same samples, the
    same classification by twin.features.MOTION_SPEED_THRESHOLD; 1e-9 relative for the order of the sums); the
    loop is drawn against the screw position, not time, and the gap's flanks ±b/2 of the centred zero are marked."""
    ds, fig = ds2_plot
    visible = [ax for ax in fig.axes if ax.get_visible()]
    assert len(visible) == 6 and visible[5].get_title().startswith("(f) hysteresis loop")
    ax = visible[5]
    means = {line.get_label(): line.get_ydata()[0] for line in ax.get_lines() if line.get_label().startswith("mean")}
    width = means["mean of d moving −"] - means["mean of d moving +"]
    assert width == pytest.approx(float(ds.backlash_hysteresis_true) * 1e6, rel=1e-9)
    assert f"{float(ds.backlash_hysteresis_true) * 1e6:.1f} µm" in ax.get_title()
    flanks = sorted(line.get_ydata()[0] for line in ax.get_lines() if line.get_linestyle() == ":")
    assert flanks == pytest.approx([-40.0, 40.0])  # ds2: 80 um backlash, thesis zero procedure
    assert "screw equivalent position" in ax.get_xlabel()
    assert ax.get_xlim() != visible[0].get_xlim()  # not on the time axis of the other panels
    time_panels = visible[:5]
    assert all(a.get_xlim() == time_panels[0].get_xlim() for a in time_panels)
    assert np.isclose(time_panels[0].get_xlim()[1], 1.5, rtol=0.1)
