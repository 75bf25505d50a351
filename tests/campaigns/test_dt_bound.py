"""One home for the coarsest integration step (issue 40, "the dt bound twice"): a campaign spec, and the CLI's
``--dt`` through the same table, accept exactly the steps the twin's solver accepts at the coarse end
(:data:`twin.solver.MAX_DT`), so a step the spec lets through is never refused by the first run."""

from __future__ import annotations

import math

import pytest
from campaign_helpers import load, write_spec

import twin
from campaigns.runner.spec import BOUNDS, SpecError
from twin.solver import MAX_DT


def test_the_spec_bounds_the_step_where_the_solver_does():
    assert BOUNDS["dt"][1] == MAX_DT


def test_the_coarsest_step_passes_both_and_the_next_one_neither(tmp_path):
    assert load(write_spec(tmp_path, f"[solver]\ndt = {MAX_DT!r}\n")).solver.dt == MAX_DT
    twin.Solver(dt=MAX_DT)
    beyond = math.nextafter(MAX_DT, math.inf)
    with pytest.raises(SpecError) as error:
        load(write_spec(tmp_path, f"[solver]\ndt = {beyond!r}\n"))
    assert any(p.startswith("solver.dt: ") and "integration step" in p for p in error.value.problems)
    with pytest.raises(twin.OptionError):
        twin.Solver(dt=beyond)
