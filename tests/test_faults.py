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

import numpy as np
import pytest

from contactqvi.case import load_case
from contactqvi.parameters import ParameterError
from contactqvi.runner import EXIT_CODES, run_case
from program_runs import run_ranks

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


def _run_until_the_first_checkpoint(tmp_path: pathlib.Path) -> tuple[subprocess.Popen, pathlib.Path, pathlib.Path]:
    """Start the 15-step Cattaneo-Mindlin case on its coarse meshes in a subprocess; return
    once step 1's checkpoint is written: the process, its output directory and the marker file."""
    text = (ROOT / "cases" / "cattaneo_mindlin_bodies.toml").read_text()
    case = tmp_path / "case.toml"
    case.write_text(text.replace('file = "../meshes/mindlin_bodies_medium.geo"',
                                 f'file = "{ROOT / "meshes" / "mindlin_bodies_coarse.geo"}"'))
    out = tmp_path / "out"
    run = subprocess.Popen([sys.executable, "-m", "contactqvi", "run", str(case), "--output", str(out), "--no-plot"],
                           stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    marker = out / "checkpoint" / "checkpoint.json"
    deadline = time.monotonic() + 300.0
    while not marker.exists():
        assert run.poll() is None and time.monotonic() < deadline, run.stderr.read() if run.poll() is not None else ""
        time.sleep(0.05)
    return run, out, marker


@pytest.mark.serial
@pytest.mark.parametrize("number", [signal.SIGTERM, signal.SIGINT])
def test_signal_stops_within_the_step_with_status_interrupted(tmp_path, number):
    """SIGTERM / SIGINT during a step of a 15-step path: exit code 3 within 10 s, the steps solved
    written, ``status = "interrupted"`` in summary.json, and the last checkpoint readable without
    the case file (adios4dolfinx, its own mesh)."""
    run, out, marker = _run_until_the_first_checkpoint(tmp_path)
    time.sleep(0.5)  # inside step 2
    os.kill(run.pid, number)
    signalled = time.monotonic()
    code = run.wait(timeout=60)
    assert code == EXIT_CODES["interrupted"], run.stderr.read()
    assert time.monotonic() - signalled < 10.0
    result = json.loads((out / "summary.json").read_text())
    assert result["status"] == "interrupted"
    *solved, last = result["steps"]
    assert len(solved) >= 1 and all(step["converged"] for step in solved)
    assert last["status"] in ("interrupted", *(["converged_rtol", "converged_atol"] if len(solved) + 1 < 15 else []))
    assert (out / "body.bp").is_dir() and (out / "contact_surface.bp").is_dir()
    _assert_checkpoint_readable(out / "checkpoint", json.loads(marker.read_text()))


@pytest.mark.serial
def test_signal_stops_a_dynamic_run_which_a_restart_continues(tmp_path):
    """SIGTERM during a time step of the shipped drop test (26 steps): exit code 3 within 10 s,
    the time steps solved in summary.json, ``status = "interrupted"``; ``--restart`` continues
    after the last checkpoint to the end (exit 0, every step converged)."""
    out = tmp_path / "out"
    command = [sys.executable, "-m", "contactqvi", "run", str(ROOT / "cases" / "drop_test.toml"), "--output", str(out),
               "--no-plot"]
    run = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    marker = out / "checkpoint" / "dynamics.json"
    deadline = time.monotonic() + 300.0
    while not marker.exists():
        assert run.poll() is None and time.monotonic() < deadline, run.stderr.read() if run.poll() is not None else ""
        time.sleep(0.05)
    os.kill(run.pid, signal.SIGTERM)
    signalled = time.monotonic()
    code = run.wait(timeout=60)
    assert code == EXIT_CODES["interrupted"], run.stderr.read()
    assert time.monotonic() - signalled < 10.0
    result = json.loads((out / "summary.json").read_text())
    assert result["status"] == "interrupted" and any(w["key"] == "signal" for w in result["warnings"])
    solved = len(result["steps"])
    assert 1 <= solved < 26 and all(step["converged"] for step in result["steps"])
    resumed = subprocess.run([*command, "--restart"], capture_output=True, text=True, timeout=600)
    assert resumed.returncode == 0, resumed.stderr
    result = json.loads((out / "summary.json").read_text())
    assert result["restarts"] == [{"after_step": solved, "mpi_size": 1}]  # continued where the signal stopped it
    assert len(result["steps"]) == 26 and all(step["converged"] for step in result["steps"])


def _checkpoint_displacement(directory: pathlib.Path, marker: dict) -> tuple[np.ndarray, np.ndarray]:
    """Node coordinates and displacement of the checkpoint, read onto its own mesh (no case file)."""
    import adios4dolfinx
    from dolfinx import fem

    msh = adios4dolfinx.read_mesh(directory / "mesh.bp", MPI.COMM_SELF, engine="BP4")
    u = fem.Function(fem.functionspace(msh, ("Lagrange", 1, (3,))), name="displacement")
    adios4dolfinx.read_function(directory / marker["file"], u, engine="BP4", time=float(marker["step"]))
    return u.function_space.tabulate_dof_coordinates(), u.x.array.reshape(-1, 3)


def _assert_checkpoint_readable(directory: pathlib.Path, marker: dict) -> None:
    """The checkpoint's displacement is the last converged step's (``solution.npz``)."""
    solution = np.load(directory.parent / "solution.npz")

    def by_position(x: np.ndarray, values: np.ndarray) -> np.ndarray:
        return values[np.lexsort(np.round(x, 12).T)]

    ours = by_position(*_checkpoint_displacement(directory, marker))
    assert np.abs(ours - by_position(solution["x"], solution["u"])).max() <= 1e-14 * np.abs(solution["u"]).max()


@pytest.mark.serial
def test_output_failing_during_the_run_is_named_and_keeps_the_last_checkpoint(tmp_path):
    """The checkpoint of step 2 cannot be written (a file is where its directory goes, as a
    full disk would fail it): exit code 4, an error naming the output, step 1's checkpoint kept."""
    run, out, marker = _run_until_the_first_checkpoint(tmp_path)
    (out / "checkpoint" / "step_0002.bp").write_text("in the way")
    code = run.wait(timeout=300)
    stderr = run.stderr.read()
    assert code == EXIT_CODES["output failed"], stderr
    assert "error: output: writing step 2" in stderr and "of step 1, is kept" in stderr
    kept = json.loads(marker.read_text())
    assert kept["step"] == 1 and len(kept["summary"]["steps"]) == 1
    _, u = _checkpoint_displacement(out / "checkpoint", kept)
    assert u[:, 2].min() == pytest.approx(-1e-3, rel=1e-12)  # step 1: the ball's face pressed down 1 mm


def test_a_mesh_gmsh_cannot_read_is_named_on_every_rank(mpi_tmp_path):
    """gmsh reads on rank 0 only; its error (a missing Include) reaches every rank as a named error
    instead of leaving the others waiting for the mesh."""
    from contactqvi.meshes import read_gmsh

    script = mpi_tmp_path / "broken.geo"
    if MPI.COMM_WORLD.rank == 0:
        script.write_text('Include "missing.geo";\n')
    MPI.COMM_WORLD.Barrier()
    with pytest.raises(ParameterError, match="mesh: gmsh cannot read .*missing.geo"):
        read_gmsh(script, MPI.COMM_WORLD)


#: Two tests under ``mpirun -n 2``: the first fails inside on_rank_0 on rank 0, the second calls a
#: collective (as conftest.py's Barrier after every test does).
RANK_0_FAILS = """
from mpi4py import MPI
from program_runs import on_rank_0


def test_fails_on_rank_0():
    def work():
        raise AssertionError("rank 0's check")
    on_rank_0(MPI.COMM_WORLD, work)


def test_then_a_collective():
    assert MPI.COMM_WORLD.allreduce(1) == MPI.COMM_WORLD.size
"""


@pytest.mark.serial
def test_a_failure_inside_on_rank_0_fails_the_test_on_every_rank(tmp_path):
    """A test failing inside tests/program_runs.py's on_rank_0 fails on every rank, and the run goes on
    to the next test: before, rank 0 went on alone and the other ranks waited in on_rank_0 for ever."""
    (tmp_path / "test_rank_0.py").write_text(RANK_0_FAILS)
    done = run_ranks([sys.executable, "-m", "mpi4py", "-m", "pytest", "-q", "--color=no", "-p", "no:cacheprovider",
                      str(tmp_path / "test_rank_0.py")], ranks=2, timeout=60.0,
                     env={"PYTHONPATH": os.pathsep.join([str(ROOT / "tests"), os.environ.get("PYTHONPATH", "")])})
    assert done.returncode != 0
    assert done.stdout.count("1 failed, 1 passed") == 2, done.stdout[-3000:]
    assert "RankZeroFailed: on rank 0: AssertionError: rank 0's check" in done.stdout, done.stdout[-3000:]


#: ``run_case`` of the patch test on 2 ranks under abort_on_error; rank 0 fails alone while recording
#: step 1 (as a failed write of its own would), the other rank goes on to step 2.
ONE_RANK_FAILS = """
import sys

from mpi4py import MPI

import contactqvi.lifetime
import contactqvi.runner as runner
from contactqvi.case import load_case, parse_case
from contactqvi.cli import abort_on_error

contactqvi.lifetime.UNWIND_TIMEOUT = 2.0
comm = MPI.COMM_WORLD
solve = runner.solve_load_path


def failing_on_rank_0(problem, steps, u, parameters, prefix, record, *args):
    def record_or_fail(*step):
        if comm.rank == 0:
            raise RuntimeError("raised on rank 0 alone")
        return record(*step)
    return solve(problem, steps, u, parameters, prefix, record_or_fail, *args)


runner.solve_load_path = failing_on_rank_0
raw = load_case(sys.argv[1]).to_dict()
raw["steps"] = [{"load": 0.5}, {"load": 1.0}]
case = parse_case(raw, sys.argv[2])
sys.exit(abort_on_error(lambda: runner.run_case(case, sys.argv[3], comm, plot=False)[1]))
"""


@pytest.mark.serial
def test_an_error_on_one_rank_ends_the_job_instead_of_hanging_in_the_clean_up(tmp_path):
    """An error raised on rank 0 alone during a run: the job ends (MPI_Abort, exit code 1) at the first
    collective clean-up, after contactqvi.lifetime.UNWIND_TIMEOUT (2 s here), naming the error. Before, rank 0
    waited for ever closing the output files (a collective) and rank 1 in step 2's solve."""
    script = tmp_path / "one_rank_fails.py"
    script.write_text(ONE_RANK_FAILS)
    started = time.monotonic()
    done = run_ranks([sys.executable, str(script), str(ROOT / "cases" / "patch_test.toml"), str(ROOT / "cases"),
                      str(tmp_path / "out")], ranks=2, timeout=120.0)
    assert done.returncode != 0 and time.monotonic() - started < 120.0
    assert "RuntimeError: raised on rank 0 alone" in done.stderr, done.stderr[-3000:]
    assert "rank 0: no other rank met an error within 2 s" in done.stderr and "MPI_ABORT" in done.stderr
