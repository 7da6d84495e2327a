"""The thermoforming demo: output files, summary status, exit codes for bad input."""

from __future__ import annotations

import json


import numpy as np
import pytest


def test_demo_test3_writes_results(mpi_tmp_path, load_demo):
    out = mpi_tmp_path / "tf"
    code = load_demo("thermoforming").main(["--test", "3", "--h", "0.1", "--output", str(out), "--log-level", "WARNING"])
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "converged" and summary["outer_iterations"] <= 5
    assert summary["residuals"][-1] <= 1e-12
    assert set(summary["comparison"]) == {"c1", "c2 (rho=0.01)", "c2 (rho=0.001)", "c2 (rho=0.0001)"}
    for name in ("membrane.png", "mould.png", "slice.png", "convergence.png", "thermoforming.bp"):
        assert (out / name).exists(), name
    with np.load(out / "solution.npz") as npz:
        assert np.all(npz["membrane"] <= npz["mould"] + 1e-12)
        assert npz["x"].shape == (121, 3)


def test_demo_test4_runs_without_plots(mpi_tmp_path, load_demo):
    out = mpi_tmp_path / "tf4"
    code = load_demo("thermoforming").main(["--test", "4", "--h", "0.05", "--no-plots", "--output", str(out), "--log-level", "WARNING"])
    assert code == 0
    assert json.loads((out / "summary.json").read_text())["status"] == "converged"


def test_demo_reports_non_convergence(mpi_tmp_path, load_demo):
    out = mpi_tmp_path / "tf_fail"
    code = load_demo("thermoforming").main(
        ["--test", "3", "--h", "0.1", "--method", "c1", "--max-iterations", "2", "--no-plots", "--output", str(out),
         "--log-level", "WARNING"]
    )
    assert code == 1
    assert json.loads((out / "summary.json").read_text())["status"] == "max_iterations"


@pytest.mark.parametrize(
    "argv, name",
    [(["--test", "5"], "test"), (["--h", "-1"], "h"), (["--method", "newton"], "method"), (["--rho-min", "2"], "rho_min"),
     (["--s-solver", "bogus"], "method"), (["--test", "2", "--projection-derivative", "radial"], "projection_derivative")],
)
def test_demo_bad_input_exits_with_a_message(argv, name, capsys, load_demo):
    code = load_demo("thermoforming").main(argv + ["--no-plots", "--no-compare", "--output", "/nonexistent-never-written"])
    assert code == 2
    assert capsys.readouterr().err.startswith(f"error: {name}:")
