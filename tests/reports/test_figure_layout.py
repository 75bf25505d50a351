"""Every figure survives real names: no tick label overlaps another or leaves the figure, no legend covers
data, and every signal a caption names is drawn. Checked on a demo-like report (seven data sets, the bench's
longest parameter names), on a 3-run report, and on `twin simulate --plot`."""

from __future__ import annotations

import dataclasses
import json
import re
from pathlib import Path

import numpy as np
import pytest

import campaigns
from campaigns.analysis.campaign_analysis import analysis_dataset
from campaigns.runner.synthetic import SYNTHETIC_CATALOG, SyntheticModel
from reports import content, figures
from reports.builder import Builder
from reports.inputs import load_inputs

DATA = Path(__file__).parent / "data"
#: The bench's longest parameter names (thesis study), given to the synthetic model's parameters.
LONG_NAMES = {
    "synthetic.gain": "sensors.preload_conditioner_sensitivity_tempco_range1",
    "synthetic.stiffness": "sensors.torque_meter_encoder_phase_asymmetry",
    "synthetic.inert": "sensors.preload_load_cell_offset_tempco_range2",
}
#: Signal words a trace caption may name; each must then be drawn (in a title, label or legend).
SIGNALS = ("position demand", "nut1 position", "linear encoder position", "screw equivalent position", "motor current",
           "current demand", "preload force", "external force", "force demand", "chamber1 pressure",
           "chamber2 pressure",
           "pressure", "current", "temperature")


def layout_problems(fig) -> list[str]:
    """Tick labels that overlap each other, text that leaves the figure, legends over plotted data."""
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    width, height = fig.bbox.width, fig.bbox.height
    problems = []

    def outside(box) -> bool:
        return box.x0 < -1 or box.y0 < -1 or box.x1 > width + 1 or box.y1 > height + 1

    for k, ax in enumerate(fig.axes):
        if not ax.get_visible():
            continue
        for name, axis in (("x", ax.xaxis), ("y", ax.yaxis)):
            low, high = sorted(axis.get_view_interval())
            span = (high - low) * 1e-9
            # the locator may place ticks beyond the view limits; only those within are drawn
            texts = [t for loc, t in zip(axis.get_majorticklocs(), axis.get_majorticklabels(), strict=False)
                     if low - span <= loc <= high + span and t.get_visible() and t.get_text()]
            offset = axis.get_offset_text()
            if offset.get_visible() and offset.get_text():
                texts.append(offset)
            boxes = [t.get_window_extent(renderer).shrunk(0.97, 0.97) for t in texts]
            for i, (text, box) in enumerate(zip(texts, boxes, strict=False)):
                if outside(box):
                    problems.append(f"axes {k}: {name} tick label {text.get_text()!r} leaves the figure")
                for other, other_box in zip(texts[i + 1:], boxes[i + 1:], strict=False):
                    if box.overlaps(other_box):
                        problems.append(
                            f"axes {k}: {name} tick labels {text.get_text()!r} and {other.get_text()!r} overlap")
        for text in (ax.title, ax.xaxis.label, ax.yaxis.label):
            if text.get_visible() and text.get_text() and outside(text.get_window_extent(renderer)):
                problems.append(f"axes {k}: {text.get_text()!r} leaves the figure")
        legend = ax.get_legend()
        if legend is not None:
            box = legend.get_window_extent(renderer)
            for line in ax.get_lines():
                points = ax.transData.transform(np.column_stack(line.get_data()).astype(float))
                inside = ((points[:, 0] > box.x0) & (points[:, 0] < box.x1)
                          & (points[:, 1] > box.y0) & (points[:, 1] < box.y1))
                if inside.any():
                    problems.append(f"axes {k}: legend covers data of {line.get_label()!r}")
                    break
    for legend in fig.legends:
        box = legend.get_window_extent(renderer)
        if outside(box):
            problems.append("figure legend leaves the figure")
        if any(box.overlaps(ax.get_window_extent(renderer)) for ax in fig.axes if ax.get_visible()):
            problems.append("figure legend lies over an axes")
    return problems


def figure_text(fig) -> str:
    """Every text drawn in a figure (titles, axis labels, tick labels, legends), lower case."""
    return " ".join(t.get_text() for t in fig.findobj(lambda a: hasattr(a, "get_text")) if t.get_text()).lower()


def _build(inputs):
    """The report model, with each figure's matplotlib Figure kept (in figure-number order)."""
    drawn = []
    original = figures._png
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(figures, "_png", lambda fig: drawn.append(fig) or original(fig))
        report = content.build(inputs, "T")
    blocks = [b for s in report.sections for b in (*report.executive, *s.blocks) if type(b).__name__ == "Figure"]
    blocks = sorted({b.number: b for b in blocks}.values(), key=lambda b: b.number)
    assert len(blocks) == len(drawn)
    return report, list(zip(blocks, drawn, strict=False)), Builder(inputs)


def _with_long_names(inputs):
    results = inputs.results.rename(LONG_NAMES)
    analysis = analysis_dataset(results)
    return dataclasses.replace(inputs, results=results, analysis=analysis)


@pytest.fixture(scope="module")
def demo_like(tmp_path_factory):
    spec = campaigns.load_spec(DATA / "demo_like.toml", catalog=SYNTHETIC_CATALOG)
    path = campaigns.run_campaign(spec, tmp_path_factory.mktemp("demo_like"), workers=1, progress=False,
                                  run_function=SyntheticModel())
    return _build(_with_long_names(load_inputs(path)))


@pytest.fixture(scope="module")
def three_runs(tmp_path_factory):
    spec = campaigns.load_spec(DATA / "campaign.toml", runs=3, catalog=SYNTHETIC_CATALOG)
    path = campaigns.run_campaign(spec, tmp_path_factory.mktemp("three"), workers=1, progress=False,
                                  run_function=SyntheticModel())
    return _build(_with_long_names(load_inputs(path)))


@pytest.mark.parametrize("name", ["demo_like", "three_runs"])
def test_no_tick_label_overlaps_or_leaves_a_figure(name, request):
    _, drawn, _ = request.getfixturevalue(name)
    problems = [f"Figure {block.number} ({block.key}): {p}" for block, fig in drawn for p in layout_problems(fig)]
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("name", ["demo_like", "three_runs"])
def test_every_signal_a_caption_names_is_drawn(name, request):
    _, drawn, builder = request.getfixturevalue(name)
    labels = [builder.describe(d) for d in builder.datasets]  # conditions in a data-set label are not signals
    checked = 0
    for block, fig in drawn:
        if not block.key.startswith("traces-"):
            continue
        caption = block.caption
        for label in labels:
            caption = caption.replace(label, "")
        text = figure_text(fig)
        missing = [s for s in SIGNALS if re.search(rf"\b{s}\b", caption.lower()) and s not in text]
        assert not missing, f"Figure {block.number} caption names {missing}, not drawn: {block.caption}"
        checked += 1
    assert checked >= 2


def test_seven_data_sets_become_small_multiples(demo_like):
    """No axes carries more than a few traces: the seven-data-set figures use one row per data set."""
    _, drawn, _ = demo_like
    for block, fig in drawn:
        for ax in fig.axes:
            assert len([line for line in ax.get_lines()
                        if not line.get_label().startswith("_")]) <= figures.MAX_TRACES + 2, block.key


def test_three_run_statistics_are_greyed_with_the_reason(three_runs):
    report, drawn, _ = three_runs
    correlations = next(s for s in report.sections if s.key == "correlations")
    # per data set either a greyed chart (an analysis that still computed the statistics) or a greyed note
    # (one that leaves them NaN); either way the reason is given, never a bare ρ = ±1
    tornadoes = [b for b in correlations.blocks if type(b).__name__ == "Figure" and b.key.startswith("tornado-")]
    notes = [b for b in correlations.blocks if type(b).__name__ == "Callout" and b.tone == "muted"]
    assert len(tornadoes) + len(notes) == 3
    assert all("insufficient data: 3 ok run(s)" in b.caption for b in tornadoes)
    assert all("insufficient data: 3 ok run(s)" in b.text for b in notes)
    tables = [b for b in correlations.blocks if type(b).__name__ == "Table"]
    assert len(tables) == 2  # Spearman/PRCC, then first-order index and effect size
    for table in tables:
        assert table.muted and all(table.muted)
        assert all("insufficient data" in row[-1] for row in table.rows)
    for block, fig in drawn:
        if block.key.startswith("tornado-"):
            assert "insufficient data" in fig.axes[0].get_title()


def test_simulate_plot_has_no_empty_panel_nor_overlaps():
    import twin
    from twin.plotting import plot_run

    fig = plot_run(twin.simulate(twin.load_scene("ds2").with_duration(1.5)))
    assert not layout_problems(fig)
    for ax in fig.axes:
        assert ax.get_lines() or not ax.get_visible(), f"empty panel {ax.get_title()!r}"
    title = fig._suptitle.get_window_extent(fig.canvas.get_renderer())
    assert title.x0 >= 0 and title.x1 <= fig.bbox.width


def test_labels_show_every_condition_that_tells_data_sets_apart(demo_like):
    _, _, builder = demo_like
    # the synthetic spec overrides external_force: the fallback reads the spec, with one unit per quantity
    assert builder.describe("ds3") == "ds3 (backlash 0 µm, preload 0 kN, external force 4 kN)"
    assert builder.describe("ds1") == "ds1 (backlash 80 µm, preload 1 kN, external force 0 kN)"


def test_labels_from_the_stored_effective_scenes(demo_like):
    """With results.attrs["dataset_conditions"] (written by the driver) a label shows the scene's own conditions."""
    _, _, builder = demo_like
    stored = {d: {"backlash": {"value": 8e-5 if d != "ds3" else 0.0, "unit": "m"},
                  "zero_procedure": {"value": "index pulse" if d == "ds2" else "hard stop", "unit": ""},
                  "room_temperature": {"value": 298.15, "unit": "K"},
                  "external_force_peak": {"value": 4000.0 if d == "ds3" else 0.0, "unit": "N"}}
              for d in builder.datasets}
    results = builder.results.assign_attrs(dataset_conditions=json.dumps(stored))
    inputs = dataclasses.replace(builder.inputs, results=results)
    relabelled = Builder(inputs)
    assert relabelled.describe("ds3") == "ds3 (backlash 0 µm, external force 4 kN, zero procedure hard stop)"
    assert relabelled.describe("ds2") == "ds2 (backlash 80 µm, external force 0 kN, zero procedure index pulse)"
    assert relabelled.conditions.common_text() == "room temperature 298 K"
