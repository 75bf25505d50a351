"""The report model: optional sections (accuracy, fidelity, bench traces) and display units."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import xarray as xr

from reports.content import build
from reports.inputs import load_inputs
from reports.model import Callout, Figure, Paragraph, Table
from reports.units import display_scale, quantity

#: Audit statements in the form the fidelity audit words them (synthetic figures; the report shows them verbatim).
_MET = ("met: mean shift +0.0018 µm (95 % t interval -0.0100 to +0.0136 µm, n = 10); tolerance 0.1000 µm, "
        "numerical floor 0.3700 µm")
_UNDETERMINED = ("undetermined: mean shift -0.1020 µm (95 % t interval -0.2000 to -0.0040 µm, n = 10); tolerance "
                 "0.1000 µm, numerical floor not measured")


def _section(report, key):
    return next(s for s in report.sections if s.key == key)


def _blocks(section, kind):
    return [b for b in section.blocks if isinstance(b, kind)]


@pytest.fixture(scope="module")
def inputs(campaign):
    return load_inputs(campaign)


@pytest.fixture(scope="module")
def report(inputs):
    return build(inputs, "T")


def test_optional_sections_say_not_available(report):
    speed, fidelity = _section(report, "speed"), _section(report, "fidelity")
    assert "not available" in _blocks(speed, Callout)[0].text
    assert not _blocks(speed, Figure)
    # the synthetic model reports no fidelity: the audit says why it did not run
    assert ("Audit result: not run (the run function reports no fidelity)."
            in [c.text for c in _blocks(fidelity, Callout)])


#: Bench-named traces added to the synthetic campaign's results: (units, values over the trace time).
BENCH_TRACES = {
    "position_demand": ("m", lambda t: 1e-2 * np.sin(t)),
    "screw_equivalent_position": ("m", lambda t: 1e-2 * np.sin(t) - 1e-6),
    "preload_force": ("N", lambda t: 1000.0 + 0 * t),
    "external_force": ("N", lambda t: 4000.0 * (t > 0.5)),
    "chamber1_pressure": ("Pa", lambda t: 6e5 + 0 * t),
    "chamber2_pressure": ("Pa", lambda t: 3e5 + 0 * t),
}


@pytest.fixture(scope="module")
def extended(campaign, tmp_path_factory):
    """A report with everything optional: a work-precision study, fidelity attributes and bench-named traces."""
    path = tmp_path_factory.mktemp("accuracy") / "work_precision.nc"
    nan = float("nan")
    xr.Dataset(  # the layout of twin accuracy's work_precision.nc
        {
            "wall_time": ("run", [0.4, 0.8, 1.1, 0.1], {"units": "s"}),
            "status": ("run", ["ok", "ok", "ok", "diverged"]),
            "feature_error": ("run", [2e-8, 1e-9, 5e-10, nan], {"units": "m"}),
        },
        coords={
            "panel": ("run", ["quantizers_off"] * 4),
            "method": ("run", ["rk4", "rk4", "scipy_radau", "semi_implicit_euler"]),
            "dt": ("run", [6.25e-5, 3.125e-5, nan, 2.5e-4]),
            "rtol": ("run", [nan, nan, 1e-6, nan]),
        },
        attrs={"scene": "nominal", "duration": 1.5, "reference": "scipy_radau rtol=1e-10",
               "quantizers_off_reference_stats": "nfev=1234, njev=56"},
    ).to_netcdf(path)
    inputs = load_inputs(campaign, accuracy_path=path)
    results = inputs.results
    time = results["trace_time"].values
    shape = (results.sizes["dataset"], results.sizes["trace_run"], len(time))
    traces = {f"trace_{name}": (("dataset", "trace_run", "trace_time"), np.broadcast_to(values(time), shape),
                                {"units": unit})
              for name, (unit, values) in BENCH_TRACES.items()}
    solved_by = np.full((results.sizes["dataset"], results.sizes["run"]), "rk4 at 62.5 us", dtype=object)
    solved_by[0, :2] = "imex_euler at 125 us"  # as the automatic integrator records it (twin.engine.solver_choice)
    solved_by[0, 2] = ""  # a run that records no method (failed before solving, or an older chunk)
    solved_by[0, 3] = "rk4 at 125 us"
    results = results.assign({**traces, "integrator": (("dataset", "run"), solved_by)}).assign_attrs(
        fidelity_ds2="pneumatics=full, current_loop=ideal", fidelity_audit="met",
        fidelity_audit_ds2=f"speedup x0.73; backlash_feature: {_MET}; max paired 0.0257 µm, MC error 0.0862 µm, KS p "
                           f"1.00 | backlash_feature_true: {_UNDETERMINED}; max paired 0.3 µm, MC error 0.1 µm, KS p "
                           "0.50",  # the format of campaigns.bench.fidelity_audit.summary_attrs
    )
    return build(dataclasses.replace(inputs, results=results), "T")


def test_speed_accuracy_section_from_a_work_precision_study(extended):
    speed = _section(extended, "speed")
    assert [f.key for f in _blocks(speed, Figure)] == ["speed-accuracy"]
    methods, study = _blocks(speed, Table)
    assert methods.rows == (("quantizers off", "rk4", "2 of 2", "0.4", "1 nm"),
                            ("quantizers off", "scipy_radau", "1 of 1", "1.1", "500 pm"),
                            ("quantizers off", "semi_implicit_euler", "0 of 1", "–", "–"))
    assert ("quantizers_off_reference_stats", "nfev=1234, njev=56") in study.rows


def test_fidelity_audit_in_words_and_micrometres(extended, inputs):
    fidelity = _section(extended, "fidelity")
    levels, integrators, audit = _blocks(fidelity, Table)
    assert levels.rows == (("ds2", "pneumatics = full, current_loop = ideal"),)
    # the method that solved each run, counted per data set from the fixture's integrator array
    names, n = [str(d) for d in inputs.results["dataset"].values], inputs.results.sizes["run"]
    assert integrators.rows == ((names[0], f"imex_euler at 125 µs: 2, rk4 at 125 µs: 1, rk4 at 62.5 µs: {n - 4}, "
                                           "not recorded: 1"),
                                *((d, f"rk4 at 62.5 µs: {n}") for d in names[1:]))
    said = next(p.text for p in _blocks(fidelity, Paragraph) if p.text.startswith("The campaign asked for integrator"))
    assert "asked for integrator 'rk4'" in said and "solved again" not in said  # how 'auto' works: only under auto
    assert audit.rows == (("ds2", "backlash_feature", _MET, "0.0257 µm", "0.0862 µm", "1.00", "0.73"),
                          ("ds2", "backlash_feature_true", _UNDETERMINED, "0.3 µm", "0.1 µm", "0.50", ""))
    assert "full-fidelity wall time / automatic wall time" in audit.caption
    assert any("speedup below 1, i.e. the automatic runs took longer" in p.text for p in _blocks(fidelity, Paragraph))


def test_fidelity_says_when_the_integrator_per_run_is_not_recorded(report):
    """The synthetic test campaign's run function does not report its method: no table, a sentence saying so."""
    fidelity = _section(report, "fidelity")
    assert not [t for t in _blocks(fidelity, Table) if t.caption.startswith("Integrator that solved")]
    assert any("which method solved each run is not recorded" in p.text for p in _blocks(fidelity, Paragraph))


def test_page_one_says_what_the_audit_checks_whatever_the_spec_asked_of_the_integrator(inputs):
    """The audit checks the automatic model simplification against full fidelity. The automatic integrator is retired
    (issue 40: twin.simulate knows no "auto" integrator), so a spec that still names it changes nothing on page 1;
    what solved each run is what the run recorded (the Fidelity section's table)."""
    def audit_callout(report):
        callouts = [c.text for c in report.executive if isinstance(c, Callout)]
        return next(text for text in callouts if text.startswith("Model check, fidelity audit ("))
    expected = "Model check, fidelity audit (automatic model simplification against full fidelity):"
    assert audit_callout(build(inputs, "T")).startswith(expected)
    spec = {**inputs.spec, "spec": {**inputs.spec["spec"], "solver": {"integrator": "auto", "fidelity": "auto"}}}
    assert audit_callout(build(dataclasses.replace(inputs, spec=spec), "T")).startswith(expected)


def test_bench_traces_get_the_thesis_panels(extended):
    """Traces named as the bench stores them give Figs. 9.6/9.7/9.11-style figures, and nut minus screw per data set."""
    keys = [f.key for f in _blocks(_section(extended, "traces"), Figure)]
    assert keys == ["traces-ds2", "traces-ds4", "traces-ds6", "traces-nut-minus-screw"]


def test_every_figure_and_table_is_numbered_in_order(report):
    blocks = [*report.executive] + [b for s in report.sections for b in s.blocks]  # page 1 first
    figures = [b for b in blocks if isinstance(b, Figure)]
    tables = [b for b in blocks if isinstance(b, Table)]
    assert [f.number for f in figures] == list(range(1, len(figures) + 1))
    assert [t.number for t in tables] == list(range(1, len(tables) + 1))
    assert all(f.png.startswith(b"\x89PNG") and len(f.caption) > 40 for f in figures)


@pytest.mark.parametrize(
    ("value", "unit", "expected"),
    [(2.5e-6, "m", "2.5 µm"), (0.012, "m", "12 mm"), (3e-16, "m", "0.3 fm"), (6e5, "Pa", "6 bar"),
     (4000.0, "N", "4 kN"), (298.15, "K", "298 K"), (0.5, "1", "0.5")],
)
def test_quantities_are_shown_with_a_readable_unit(value, unit, expected):
    assert quantity(value, unit) == expected


def test_display_scale_ignores_non_finite_values():
    assert display_scale("m", [np.nan, 3e-6, -5e-6]) == (1e6, "µm")
    assert display_scale("m", [np.nan]) == (1.0, "m")


def test_a_data_set_without_successful_runs(inputs):
    """Every figure still draws (warnings are errors in the test suite) and the failures are reported."""
    from campaigns.analysis.campaign_analysis import analysis_dataset

    status = inputs.results["status"].copy()
    status.loc[{"dataset": "ds4"}] = "error"
    results = inputs.results.assign(status=status)
    report = build(dataclasses.replace(inputs, results=results, analysis=analysis_dataset(results)), "T")
    failures = _section(report, "failures")
    assert _blocks(failures, Callout)[0].text.startswith("32 of 90 runs failed")
    assert any(f.key == "distribution-backlash_feature" for f in _blocks(_section(report, "distributions"), Figure))
    assert any(c.text.startswith("backlash_feature: insufficient data: ds4 has 0 ok runs")
               for c in _blocks(_section(report, "observability"), Callout))
