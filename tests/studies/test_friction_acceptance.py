"""The friction acceptance study's pieces without engine runs (app.studies.friction_convergence, issue 41): the
campaign's own runs, the arms, the paired shifts and the free-nut figures on traces with known answers."""

import math

import numpy as np
import pytest
import xarray as xr
from scipy.stats import t as student_t

import twin
from app.studies import friction_convergence as fc
from campaigns.bench.campaign import load_spec
from campaigns.bench.solver_accuracy import THESIS_SPEC
from campaigns.runner.execution import build_request
from campaigns.runner.sampling import sample

PARAMS = twin.load_parameters()


def test_the_requests_are_the_thesis_campaigns_own_runs():
    spec = load_spec(THESIS_SPEC)
    short = spec.model_copy(update={"runs_per_dataset": 3})
    samples = sample(short)
    names = [d.name for d in spec.datasets]
    for request in fc.thesis_requests(["ds4", "ds2"], range(3)):
        expected = build_request(short, samples, names.index(request.dataset), request.run_index)
        assert request.parameter_values == expected.parameter_values
        assert request.conditions == expected.conditions
        assert request.noise_rng().random() == expected.noise_rng().random()


def test_the_stiffness_sensitivity_keeps_the_presliding_damping_ratio():
    m = PARAMS.value("pneumatics.piston_mass")

    def ratio(stiffness, damping):
        return damping / (2.0 * math.sqrt(stiffness * m))

    nominal = ratio(PARAMS.value("pneumatics.friction_presliding_stiffness"),
                    PARAMS.value("pneumatics.friction_bristle_damping"))
    for stiffness in (2.0e6, 4.0e7):
        values = dict(fc.presliding_stiffness_values(stiffness, PARAMS))
        assert values["pneumatics.friction_presliding_stiffness"] == stiffness
        assert ratio(stiffness, values["pneumatics.friction_bristle_damping"]) == pytest.approx(nominal, rel=1e-12)
        PARAMS.with_values(values)   # inside the parameters' bounds


def test_every_pairing_compares_two_arms_that_differ_in_what_it_names():
    arms = {a.name: a for a in fc.acceptance_arms(PARAMS)}
    assert len(arms) == len(fc.acceptance_arms(PARAMS))
    for candidate, reference, _ in fc.ACCEPTANCE_PAIRINGS:
        assert candidate in arms and reference in arms
    step = arms["elasto_plastic_half_step"]
    assert (step.step_factor, step.seal_friction, step.parameters) == (0.5, "elasto_plastic", ())
    assert arms["regularised_half_v_th"].parameters == (
        ("pneumatics.friction_velocity_threshold", PARAMS.value("pneumatics.friction_velocity_threshold") / 2),)


def _study(differences, base=2.0e-6):
    n = differences.size
    values = np.stack([np.full(n, base), base + differences])[:, None, :]
    study = xr.Dataset({f: (("arm", "dataset", "run"), values) for f in fc.ACCEPTANCE_FEATURES},
                       coords={"arm": ["elasto_plastic", "elasto_plastic_half_step"], "dataset": ["ds4"],
                               "run": np.arange(n)})
    study["status"] = (("arm", "dataset", "run"), np.full(values.shape, "ok"))
    return study


def test_the_paired_shift_is_the_mean_difference_with_its_student_t_interval():
    rng = np.random.default_rng(3)
    d = rng.normal(0.01e-6, 0.05e-6, 40)
    shifts = fc.paired_shifts(_study(d)).sel(pairing="elasto_plastic_half_step", dataset="ds4",
                                              feature="backlash_feature")
    half = student_t.ppf(0.975, d.size - 1) * d.std(ddof=1) / math.sqrt(d.size)
    assert float(shifts["mean"]) == pytest.approx(d.mean(), rel=1e-9)
    assert float(shifts.upper - shifts.lower) == pytest.approx(2 * half, rel=1e-9)
    assert int(shifts.n) == 40 and shifts.verdict.item() == "met"
    assert shifts.reference.item() == "elasto_plastic"


def test_a_shift_beyond_the_tolerance_is_not_met_and_too_few_pairs_are_insufficient():
    far = fc.paired_shifts(_study(np.full(30, 0.2e-6) + np.linspace(-1e-9, 1e-9, 30)))
    assert far.verdict.sel(dataset="ds4", feature="backlash_hysteresis").item() == "not met"
    few = fc.paired_shifts(_study(np.zeros(10)))
    assert few.verdict.sel(dataset="ds4", feature="backlash_feature").item() == "insufficient data"


def _trace(t, rel, force, piston):
    zeros = np.zeros_like(t)
    return xr.Dataset({"nut1_position": ("time", rel), "screw_equivalent_position": ("time", zeros),
                       "external_force": ("time", force), "force_demand": ("time", zeros),
                       "piston_position": ("time", piston), "nut1_contact_force": ("time", force)},
                      coords={"time": t})


def test_rest_figures_read_a_known_limit_cycle():
    t = np.arange(0.0, 10.0, fc.TRACE_SPACING)
    period, amplitude = 0.128, 45e-6
    rel = amplitude * np.sign(np.sin(2 * np.pi * t / period))
    force = 300.0 * np.sin(2 * np.pi * t / period)
    figures = fc.rest_figures(_trace(t, rel, force, 1e-3 * np.ones_like(t)))
    assert figures["period"] == pytest.approx(period, abs=2 * fc.TRACE_SPACING)
    assert figures["nut_peak_to_peak"] == pytest.approx(2 * amplitude)
    assert figures["force_error_rms"] == pytest.approx(300.0 / math.sqrt(2), rel=0.02)
    assert figures["piston_speed_rms"] == 0.0
    held = fc.rest_figures(_trace(t, np.zeros_like(t), np.zeros_like(t), np.zeros_like(t)))
    assert math.isnan(held["period"]) and held["nut_peak_to_peak"] == 0.0


def test_contact_oscillation_finds_a_burst_its_frequency_and_when():
    t = np.arange(0.0, 10.0, fc.TRACE_SPACING)
    burst = (t > 6.8) & (t < 7.5)
    force = 50.0 * np.sin(2 * np.pi * 1.0 * t) + np.where(burst, 500.0 * np.sin(2 * np.pi * 255.0 * t), 0.0)
    found = fc.contact_oscillation(_trace(t, np.zeros_like(t), force, np.zeros_like(t)))
    assert found["frequency"] == pytest.approx(255.0, abs=1.0 / fc.OSCILLATION_WINDOW)
    assert 6.6 <= found["start"] <= 7.5 - fc.OSCILLATION_WINDOW + 0.01
    # the high-pass removes a centred moving average of N samples, whose gain at f is sin(pi f N dt) / (N sin(pi f
    # dt)) (the Dirichlet kernel): what is left of the 255 Hz burst is its amplitude times one minus that gain
    n, dt = fc.HIGH_PASS_SAMPLES, fc.TRACE_SPACING
    gain = math.sin(math.pi * 255.0 * n * dt) / (n * math.sin(math.pi * 255.0 * dt))
    assert found["rms"] == pytest.approx(500.0 / math.sqrt(2) * (1.0 - gain), rel=0.02)


def test_the_default_arm_is_the_campaigns_run_bit_for_bit_and_the_half_step_halves_it():
    """The elasto-plastic arm (the default seal level) at the campaign step is what the campaign's run function
    returns for the same request (same parameters, noise, fidelity and step), to the last bit; the half-step arm runs
    at half of that step."""
    from campaigns.bench.adapter import simulate_run

    arms = {a.name: a for a in fc.acceptance_arms(PARAMS)}
    study = fc.paired_study([arms["elasto_plastic"], arms["elasto_plastic_half_step"]], ["ds4"], range(1),
                            progress=lambda line: None)
    request = fc.thesis_requests(["ds4"], range(1))[0]
    campaign = simulate_run(request)
    assert campaign["status"] == "ok" and (study.status == "ok").all()
    for feature in fc.ACCEPTANCE_FEATURES:
        assert float(study[feature].sel(arm="elasto_plastic", dataset="ds4", run=0)) == campaign["features"][feature]
    steps = study.dt.sel(dataset="ds4", run=0)
    assert float(steps.sel(arm="elasto_plastic_half_step")) == float(steps.sel(arm="elasto_plastic")) / 2.0
