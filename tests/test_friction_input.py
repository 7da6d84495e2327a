"""Bad input gives a clear error naming the parameter; the demo runs end to end."""

from __future__ import annotations

import json

from mpi4py import MPI

import pytest

from contactqvi.friction import FrictionProblem, PrimalDualActiveSet, augmented_lagrangian, uzawa
from contactqvi.meshes import create_unit_square
from contactqvi.parameters import ParameterError
from contactqvi.problems.stadler import create_stadler_problem, stadler_example


def _square(n: int = 4):
    return create_unit_square(MPI.COMM_WORLD, n)


@pytest.mark.parametrize(
    "kwargs, name",
    [
        ({"g": -1.0, "mu": 0.5, "dirichlet": ()}, "g"),
        ({"g": 0.0, "mu": 0.5, "dirichlet": ()}, "g"),
        ({"g": 1.0, "mu": -0.5, "dirichlet": ()}, "mu"),
        ({"g": 1.0, "mu": 0.0, "dirichlet": ()}, "mu"),
        ({"g": 1.0, "mu": -1.0, "dirichlet": ("left",)}, "mu"),
    ],
)
def test_problem_rejects_bad_data(kwargs, name):
    msh, tags = _square()
    with pytest.raises(ParameterError, match=rf"^{name}:") as info:
        FrictionProblem(msh, tags, ("top", "bottom"), kwargs["dirichlet"], lambda x: x[0], kwargs["mu"], kwargs["g"])
    assert info.value.name == name


def test_solvers_reject_bad_parameters():
    problem = create_stadler_problem(MPI.COMM_WORLD, stadler_example(2), 5)
    pdas = PrimalDualActiveSet(problem)
    for gamma in (0.0, -1.0, float("inf")):
        with pytest.raises(ParameterError, match="^gamma:"):
            pdas.solve(gamma)
        with pytest.raises(ParameterError, match="^gamma:"):
            uzawa(problem, gamma)
        with pytest.raises(ParameterError, match="^gamma:"):
            augmented_lagrangian(pdas, gamma)
    for sigma in (0.0, -2.0):
        with pytest.raises(ParameterError, match="^sigma:"):
            pdas.solve(10.0, sigma)
    with pytest.raises(ParameterError, match="^gamma:"):
        augmented_lagrangian(pdas, lambda step: -1.0)
    with pytest.raises(ParameterError, match="^inner:"):
        augmented_lagrangian(pdas, 10.0, inner="sloppy")
    with pytest.raises(ParameterError, match="^max_iterations:"):
        pdas.solve(10.0, max_iterations=0)


def test_examples_reject_bad_input():
    for number in (0, 4):
        with pytest.raises(ParameterError, match="^example:"):
            stadler_example(number)
    for N in (2, 0, 3.5):
        with pytest.raises(ParameterError, match="^N:"):
            create_stadler_problem(MPI.COMM_WORLD, stadler_example(1), N)


@pytest.mark.parametrize(
    "argv, name",
    [
        (["--example", "4"], "example"),
        (["--method", "newton"], "method"),
        (["--gamma", "0"], "gamma"),
        (["--sigma", "-1"], "sigma"),
        (["--N", "2"], "N"),
        (["--alm-inner", "maybe"], "alm-inner"),
        (["--example", "2", "--g", "-0.4"], "g"),
        (["--example", "3", "--mu", "-0.5"], "mu"),
        (["--example", "3", "--mu", "0"], "mu"),
        (["--max-iterations", "0"], "max-iterations"),
        (["--method", "alm", "--alm-steps", "0"], "alm-steps"),
        (["--method", "uzawa", "--tol=-1e-4"], "tol"),
        (["--example2-reading", "x2x2"], "example2-reading"),
    ],
)
def test_demo_reports_bad_input(argv, name, capsys, mpi_tmp_path, load_demo):
    rc = load_demo("simplified_friction").main([*argv, "--output", str(mpi_tmp_path / "bad"), "--no-png"])
    assert rc == 2
    if MPI.COMM_WORLD.rank == 0:
        assert f"error: {name}:" in capsys.readouterr().err


def test_demo_alm_end_to_end(mpi_tmp_path, load_demo):
    out = mpi_tmp_path / "alm"
    argv = ["--example", "2", "--method", "alm", "--alm-inner", "inexact", "--alm-schedule", "power10",
            "--alm-steps", "5", "--tol", "1e-8", "--N", "9", "--output", str(out), "--no-png"]  # fmt: skip
    assert load_demo("simplified_friction").main(argv) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "converged" and summary["d_lambda"] < 1e-8
    assert summary["max_abs_lambda"] <= 0.4 * (1 + 1e-14)
    assert (out / "solution.npz").is_file() and (out / "solution.bp").is_dir()
    assert summary["gamma"] == "10^l" and [h["gamma"] for h in summary["history"]] == [10.0**k for k in range(1, 6)]


def test_demo_alm_passes_sigma_to_the_inner_pdas(mpi_tmp_path, load_demo):
    """sigma reaches ALM's inner PDAS: on Example 2, sigma = 1 converges and sigma = 1e-3 makes its sets cycle."""
    statuses = {}
    for sigma in ("1", "1e-3"):
        out = mpi_tmp_path / f"alm_sigma_{sigma}"
        argv = ["--example", "2", "--method", "alm", "--alm-inner", "inexact", "--gamma", "1e2", "--sigma", sigma,
                "--alm-steps", "3", "--N", "17", "--output", str(out), "--no-png"]  # fmt: skip
        rc = load_demo("simplified_friction").main(argv)
        summary = json.loads((out / "summary.json").read_text())
        assert summary["sigma"] == float(sigma)
        statuses[sigma] = (rc, summary["status"], summary["converged"])
    assert statuses == {"1": (0, "completed", True), "1e-3": (1, "inner_cycling", False)}


def test_demo_uzawa_without_reference_stops_on_the_multiplier_change(mpi_tmp_path, load_demo):
    out = mpi_tmp_path / "uzawa_noref"
    argv = ["--method", "uzawa", "--gamma", "10", "--N", "9", "--no-reference", "--output", str(out), "--no-png"]
    assert load_demo("simplified_friction").main(argv) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["d_lambda"] is None
    assert summary["history"][-1]["lambda_change"] < 1e-4 <= summary["history"][-2]["lambda_change"]


def test_demo_uzawa_nonconvergence_exit_code(mpi_tmp_path, load_demo):
    out = mpi_tmp_path / "uzawa"
    argv = ["--example", "2", "--method", "uzawa", "--gamma", "1000", "--max-iterations", "1",
            "--N", "9", "--output", str(out), "--no-png"]  # fmt: skip
    assert load_demo("simplified_friction").main(argv) == 1
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "max_iterations" and summary["iterations"] == 20 and not summary["converged"]
