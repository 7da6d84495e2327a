"""The shared solver core: Status, Result, Parameters, KSP presets."""

from __future__ import annotations

import argparse

import pytest

from contactqvi.linalg import KSP_PRESETS, preset
from contactqvi.parameters import Parameter, ParameterError, Parameters
from contactqvi.result import Result, Status

pytestmark = pytest.mark.one_rank(reason="Status, Result, parameter tables and KSP presets as Python data: no communicator")

TABLE = Parameters(
    tol=Parameter(0.1, "inner tolerance", minimum=0.0, maximum=1.0, exclusive=True),
    max_iterations=Parameter(100, "iteration limit", type=int, minimum=1),
    rule=Parameter("alpha", "a rule", type=str, choices=("alpha", "beta")),
    gamma=Parameter(None, "gamma", minimum=0.0, exclusive=True, optional=True),
    eliminate=Parameter(True, "eliminate", type=bool),
)


def test_status_names_and_signs():
    converged = {s.name for s in Status if s.converged}
    assert converged == {"CONVERGED_RTOL", "CONVERGED_ATOL", "CONVERGED_ACTIVE_SET", "CONVERGED_STEP",
                         "CONVERGED_INEXACT", "CONVERGED_ITERATIONS"}
    assert str(Status.DIVERGED_LINE_SEARCH) == "diverged_line_search"
    result = Result(status=Status.CONVERGED_RTOL, iterations=3)
    assert result.converged and result.summary()["status"] == "converged_rtol"
    for _ in range(2):
        with result.timings.phase("solve"):
            sum(range(10000))
    assert result.timings["solve"] > 0.0 and list(result.timings) == ["solve"]
    assert not Result(status=Status.DIVERGED_MAX_IT, iterations=3).converged


def test_parameters_merge_and_convert():
    p = TABLE.check({"tol": 1e-2, "max_iterations": 5.0, "rule": "beta"})
    assert p == {"tol": 1e-2, "max_iterations": 5, "rule": "beta", "gamma": None, "eliminate": True}
    assert isinstance(p["max_iterations"], int)


@pytest.mark.parametrize(
    "given, text",
    [
        ({"tol": 1.0}, "tol: must be in (0, 1), got 1.0"),
        ({"tol": float("nan")}, "tol: must be a finite number"),
        ({"max_iterations": 0}, "max_iterations: must be >= 1, got 0"),
        ({"max_iterations": 2.5}, "max_iterations: must be an integer"),
        ({"rule": "alpa"}, "rule: must be one of alpha, beta, got 'alpa' (did you mean 'alpha'?)"),
        ({"gamma": -1.0}, "gamma: must be > 0"),
        ({"eliminate": "yes"}, "eliminate: must be true or false"),
        ({"tl": 0.1}, "tl: unknown parameter; did you mean 'tol'?"),
    ],
)
def test_parameters_reject_bad_values_by_name(given, text):
    with pytest.raises(ParameterError) as info:
        TABLE.check(given)
    assert str(info.value).startswith(text)


def test_parameters_on_the_command_line():
    parser = argparse.ArgumentParser()
    TABLE.add_arguments(parser)
    args = parser.parse_args(["--tol", "0.01", "--max-iterations", "7", "--no-eliminate", "--gamma", "none"])
    assert TABLE.from_namespace(args) == {
        "tol": 0.01, "max_iterations": 7, "rule": "alpha", "gamma": None, "eliminate": False
    }
    with pytest.raises(ParameterError, match="tol: must be in"):
        TABLE.from_namespace(parser.parse_args(["--tol", "2"]))


def test_presets_are_copies_and_checked():
    options = preset("lu", ksp_monitor=None)
    assert options["pc_factor_mat_solver_type"] == "mumps" and "ksp_monitor" in options
    assert "ksp_monitor" not in KSP_PRESETS["lu"]
    with pytest.raises(ParameterError, match="pc: must be one of"):
        preset("lux")
