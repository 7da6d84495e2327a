"""The thermoforming demo: output files, summary status, exit codes for bad input."""

from __future__ import annotations

import json
import logging

from mpi4py import MPI

import numpy as np
import pytest


@pytest.fixture(autouse=True)
def _drop_demo_log_handlers():
    """The demo logs to the sys.stdout of its call, which pytest closes after the test."""
    yield
    for handler in logging.root.handlers[:]:
        logging.root.removeHandler(handler)


def test_demo_test3_writes_results(mpi_tmp_path, load_demo):
    out = mpi_tmp_path / "tf"
    code = load_demo("thermoforming").main(["--test", "3", "--h", "0.1", "--output", str(out), "--log-level", "WARNING"])
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "converged_atol" and summary["converged"] and summary["iterations"] <= 5
    assert summary["history"][-1]["residual"] <= 1e-12
    assert set(summary["comparison"]) == {"c1", "c2 (rho=0.01)", "c2 (rho=0.001)", "c2 (rho=0.0001)"}
    # the checked values of every parameter table, defaults filled in per test
    assert summary["parameters"]["outer"]["atol"] == 1e-12 and summary["parameters"]["obstacle"]["rho_min"] == 1e-6
    for name in ("membrane.png", "mould.png", "slice.png", "convergence.png", "thermoforming.bp"):
        assert (out / name).exists(), name
    with np.load(out / "solution.npz") as npz:
        assert np.all(npz["u"] <= npz["mould"] + 1e-12)
        assert npz["x"].shape == (121, 3)


def test_demo_test4_runs_without_plots(mpi_tmp_path, load_demo):
    out = mpi_tmp_path / "tf4"
    code = load_demo("thermoforming").main(["--test", "4", "--h", "0.05", "--no-plots", "--output", str(out), "--log-level", "WARNING"])
    assert code == 0
    assert json.loads((out / "summary.json").read_text())["status"] == "converged_atol"


def test_demo_reports_non_convergence(mpi_tmp_path, load_demo):
    out = mpi_tmp_path / "tf_fail"
    code = load_demo("thermoforming").main(
        ["--test", "3", "--h", "0.1", "--method", "c1", "--max-iterations", "2", "--no-plots", "--output", str(out),
         "--log-level", "WARNING"]
    )
    assert code == 1
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "diverged_max_it" and not summary["converged"]


def _exit_code(main, argv: list[str]) -> int:
    try:
        return main(argv)
    except SystemExit as exc:  # argparse rejects a value outside a parameter's choices
        return exc.code


@pytest.mark.parametrize(
    "argv, text",
    [(["--test", "5"], "error: test: must be in [1, 4]"), (["--h", "-1"], "error: h: must be > 0"),
     (["--rho-min", "2"], "error: rho_min: must be < rho0"), (["--rho-factor", "1"], "error: rho_factor: must be > 1"),
     (["--method", "newton"], "argument --method: invalid choice"),
     (["--s-solver", "bogus"], "argument --s-solver: invalid choice"),
     (["--test", "2", "--projection-derivative", "radial"], "argument --projection-derivative: invalid choice")],
)  # fmt: skip
def test_demo_bad_input_exits_with_a_message(argv, text, capsys, load_demo):
    code = _exit_code(load_demo("thermoforming").main, argv + ["--no-plots", "--no-compare", "--output", "/nonexistent-never-written"])
    assert code == 2
    assert capsys.readouterr().err.count(text) == (MPI.COMM_WORLD.rank == 0)  # argparse's messages too


def test_demo_help_names_its_own_petsc_prefix(capsys, load_demo):
    assert _exit_code(load_demo("thermoforming").main, ["--help"]) == 0
    text = capsys.readouterr().out
    assert "-obstacle_pfmy_snes_monitor" in text and "-coulomb_" not in text
