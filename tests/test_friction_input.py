"""Bad input gives a clear error naming the parameter; the demo runs end to end."""

from __future__ import annotations

import json

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi.friction import (
    FrictionActiveSetSolver,
    FrictionProblem,
    UzawaSolver,
    augmented_lagrangian,
    create_problem,
)
from contactqvi.meshes import create_unit_square
from contactqvi.parameters import ParameterError
from contactqvi.problems.stadler import stadler_example


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
    """The parameter tables check every value before any work, with the shared error text."""
    problem = create_problem(MPI.COMM_WORLD, stadler_example(2), N=5)
    with problem, FrictionActiveSetSolver(problem) as pdas, UzawaSolver(problem) as uzawa:
        for gamma in (0.0, -1.0, float("inf")):
            for solve in (pdas.solve, uzawa.solve, lambda **kw: augmented_lagrangian(pdas, **kw)):
                with pytest.raises(ParameterError, match="^gamma: must be"):
                    solve(gamma=gamma)
        for sigma in (0.0, -2.0):
            with pytest.raises(ParameterError, match="^sigma: must be > 0"):
                pdas.solve(gamma=10.0, sigma=sigma)
        with pytest.raises(ParameterError, match="^inner: must be one of exact, inexact, got 'sloppy'"):
            augmented_lagrangian(pdas, inner="sloppy")
        with pytest.raises(ParameterError, match="^schedule: must be one of"):
            augmented_lagrangian(pdas, schedule="power2")
        with pytest.raises(ParameterError, match="^max_iterations: must be >= 1, got 0"):
            pdas.solve(gamma=10.0, max_iterations=0)
        with pytest.raises(ParameterError, match="^max_iterations: must be an integer"):
            uzawa.solve(max_iterations=2.5)
        with pytest.raises(ParameterError, match="^residual_reduction: must be in"):
            pdas.solve(residual_reduction=1.0)
        with pytest.raises(ParameterError, match="^lam_hat:"):
            pdas.solve(lam_hat=np.zeros(len(problem.boundary_dofs) + 1))
        with pytest.raises(ParameterError, match="^gama: unknown parameter; did you mean 'gamma'"):
            pdas.solve(gama=10.0)


def test_examples_reject_bad_input():
    for number in (0, 4):
        with pytest.raises(ParameterError, match="^example: must be in"):
            stadler_example(number)
    with pytest.raises(ParameterError, match="^example2_reading: must be one of"):
        stadler_example(2, "x2x2")
    with pytest.raises(ParameterError, match="^g: must be > 0"):
        stadler_example(2, g=0.0)
    for N in (2, 0, 3.5):
        with pytest.raises(ParameterError, match="^N:"):
            create_problem(MPI.COMM_WORLD, stadler_example(1), N=N)
    with pytest.raises(ParameterError, match="^discretisation: must be one of q1, p1, fd"):
        create_problem(MPI.COMM_WORLD, stadler_example(1), N=5, discretisation="q2")


@pytest.mark.parametrize(
    "argv, name",
    [
        (["--example", "4"], "example"),
        (["--gamma", "0"], "gamma"),
        (["--sigma", "-1"], "sigma"),
        (["--N", "2"], "N"),
        (["--example", "2", "--g", "-0.4"], "g"),
        (["--example", "3", "--mu", "-0.5"], "mu"),
        (["--example", "3", "--mu", "0"], "mu"),
        (["--max-iterations", "0"], "max_iterations"),
        (["--method", "alm", "--max-outer", "0"], "max_outer"),
        (["--method", "alm", "--residual-reduction", "2"], "residual_reduction"),
        (["--method", "ss", "--gamma", "-1"], "gamma"),
        (["--method", "uzawa", "--atol=-1e-4"], "atol"),
    ],
)
def test_demo_reports_bad_input(argv, name, capsys, mpi_tmp_path, load_demo):
    rc = load_demo("simplified_friction").main([*argv, "--output", str(mpi_tmp_path / "bad"), "--no-png"])
    assert rc == 2
    assert capsys.readouterr().err.count(f"error: {name}: must") == (MPI.COMM_WORLD.rank == 0)


@pytest.mark.parametrize(
    "argv",
    [["--method", "newton"], ["--inner", "maybe", "--method", "alm"], ["--example2-reading", "x2x2"],
     ["--discretisation", "q2"]],
)  # fmt: skip
def test_demo_rejects_bad_choices(argv, capsys, mpi_tmp_path, load_demo):
    """Choices are checked by argparse (exit code 2, the option and the valid values named)."""
    with pytest.raises(SystemExit) as info:
        load_demo("simplified_friction").main([*argv, "--output", str(mpi_tmp_path / "bad"), "--no-png"])
    assert info.value.code == 2
    if MPI.COMM_WORLD.rank == 0:
        assert f"argument {argv[0]}: invalid choice" in capsys.readouterr().err


@pytest.mark.parametrize("method, options", [("pdas", ["--sigma", "--max-iterations"]),
                                             ("alm", ["--inner", "--schedule", "--atol", "--max-inner"]),
                                             ("uzawa", ["--atol", "--max-iterations"])])  # fmt: skip
def test_demo_help_names_its_own_petsc_prefix(method, options, capsys, load_demo):
    with pytest.raises(SystemExit):
        load_demo("simplified_friction").main(["--method", method, "--help"])
    text = capsys.readouterr().out
    assert "-friction_ksp_view" in text and "-uzawa_ksp_view" in text and "coulomb" not in text
    assert all(option in text for option in ["--gamma", *options, "--discretisation", "--example"]), text


def test_demo_alm_end_to_end(mpi_tmp_path, load_demo):
    out = mpi_tmp_path / "alm"
    argv = ["--example", "2", "--method", "alm", "--inner", "inexact", "--schedule", "power10",
            "--max-outer", "5", "--atol", "1e-8", "--N", "9", "--output", str(out)]  # fmt: skip
    assert load_demo("simplified_friction").main(argv) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "converged_atol" and summary["converged"] and summary["d_lambda"] < 1e-8
    assert summary["max_abs_lambda"] <= 0.4 * (1 + 1e-14)
    assert (out / "solution.npz").is_file() and (out / "solution.bp").is_dir() and (out / "y.png").is_file()
    solver = summary["parameters"]["solver"]
    assert solver["schedule"] == "power10" and solver["max_outer"] == 5 and solver["atol"] == 1e-8
    assert [h["gamma"] for h in summary["history"]] == [10.0**k for k in range(1, 6)]
    assert summary["parameters"]["problem"] == {"example": 2, "N": 9, "discretisation": "q1", "g": None, "mu": None,
                                                "example2_reading": "x1x2"}  # fmt: skip
    if MPI.COMM_WORLD.rank == 0:
        npz = np.load(out / "solution.npz")
        assert len(npz["lam"]) == len(npz["boundary_x"]) == summary["friction_nodes"]


def test_demo_alm_passes_sigma_to_the_inner_pdas(mpi_tmp_path, load_demo):
    """sigma reaches ALM's inner PDAS: on Example 2, sigma = 1 converges and sigma = 1e-3 makes its sets cycle."""
    statuses = {}
    for sigma in ("1", "1e-3"):
        out = mpi_tmp_path / f"alm_sigma_{sigma}"
        argv = ["--example", "2", "--method", "alm", "--inner", "inexact", "--gamma", "1e2", "--sigma", sigma,
                "--max-outer", "3", "--N", "17", "--output", str(out), "--no-png"]  # fmt: skip
        rc = load_demo("simplified_friction").main(argv)
        summary = json.loads((out / "summary.json").read_text())
        assert summary["parameters"]["solver"]["sigma"] == float(sigma)
        statuses[sigma] = (rc, summary["status"], summary["converged"])
    assert statuses == {"1": (0, "converged_iterations", True), "1e-3": (1, "diverged_inner", False)}


@pytest.mark.parametrize("discretisation", ["q1", "fd"])
def test_demo_uzawa_without_reference_stops_on_the_multiplier_change(discretisation, mpi_tmp_path, load_demo):
    out = mpi_tmp_path / f"uzawa_noref_{discretisation}"
    argv = ["--method", "uzawa", "--gamma", "5", "--N", "9", "--discretisation", discretisation,
            "--no-reference", "--output", str(out), "--no-png"]  # fmt: skip
    assert load_demo("simplified_friction").main(argv) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["d_lambda"] is None and summary["status"] == "converged_step"
    assert summary["history"][-1]["lambda_change"] < 1e-4 <= summary["history"][-2]["lambda_change"]


def test_demo_uzawa_nonconvergence_exit_code(mpi_tmp_path, load_demo):
    out = mpi_tmp_path / "uzawa"
    argv = ["--example", "2", "--method", "uzawa", "--gamma", "1000", "--max-iterations", "20",
            "--N", "9", "--output", str(out), "--no-png"]  # fmt: skip
    assert load_demo("simplified_friction").main(argv) == 1
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "diverged_max_it" and summary["iterations"] == 20 and not summary["converged"]
