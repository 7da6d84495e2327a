"""Runs that meet faults (issue 24): a signal from the batch system or Ctrl-C, an output
directory that cannot be written."""

from __future__ import annotations

import json
import os
import pathlib
import signal
import subprocess
import sys
import time

from mpi4py import MPI

import pytest

from contactqvi.case import load_case
from contactqvi.parameters import ParameterError
from contactqvi.runner import EXIT_CODES, run_case

ROOT = pathlib.Path(__file__).resolve().parent.parent


def test_unwritable_output_is_named_before_the_mesh_is_read(mpi_tmp_path):
    """An output directory below a regular file cannot be made: a named error, and nothing ran."""
    blocker = mpi_tmp_path / "a_file"
    if MPI.COMM_WORLD.rank == 0:
        blocker.write_text("not a directory")
    MPI.COMM_WORLD.Barrier()
    case = load_case(ROOT / "cases" / "patch_test.toml")
    started = time.perf_counter()
    with pytest.raises(ParameterError, match="output: cannot write to the output directory"):
        run_case(case, blocker / "out", plot=False)
    assert time.perf_counter() - started < 5.0  # before meshing and assembly


@pytest.mark.serial
@pytest.mark.parametrize("number", [signal.SIGTERM, signal.SIGINT])
def test_signal_stops_after_the_step_with_status_interrupted(tmp_path, number):
    """SIGTERM / SIGINT during a 15-step path: exit code 3 within 10 s, the steps solved written,
    ``status = "interrupted"`` in summary.json."""
    text = (ROOT / "cases" / "cattaneo_mindlin_bodies.toml").read_text()
    mesh = ROOT / "meshes" / "mindlin_bodies_coarse.geo"
    case = tmp_path / "case.toml"
    case.write_text(text.replace('file = "../meshes/mindlin_bodies_medium.geo"', f'file = "{mesh}"'))
    out = tmp_path / "out"
    run = subprocess.Popen([sys.executable, "-m", "contactqvi", "run", str(case), "--output", str(out), "--no-plot"],
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    summary = out / "summary.json"
    deadline = time.monotonic() + 300.0
    while not (summary.exists() and json.loads(summary.read_text())["steps"]):
        assert run.poll() is None and time.monotonic() < deadline, run.stderr.read() if run.poll() is not None else ""
        time.sleep(0.2)
    os.kill(run.pid, number)
    signalled = time.monotonic()
    code = run.wait(timeout=60)
    assert code == EXIT_CODES["interrupted"], run.stderr.read()
    assert time.monotonic() - signalled < 10.0
    result = json.loads(summary.read_text())
    assert result["status"] == "interrupted"
    assert 1 <= len(result["steps"]) < 15 and all(step["converged"] for step in result["steps"])
    assert (out / "body.bp").is_dir() and (out / "contact_surface.bp").is_dir()
