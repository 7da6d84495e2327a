"""Kill and restart (issue 24): a run killed with SIGKILL in the middle of a load step and
continued with ``--restart`` ends as the uninterrupted run does.

Two bodies (Cattaneo-Mindlin, coarse meshes, the indentation and the first two
tangential steps: the variant of the shipped case that tests/shipped_runs.py runs, the
uninterrupted run), killed once in the second tangential step, so the checkpoint carries
mortar relative displacements, nodal frames and the previous step's slip. Continued on the
same number of ranks the restart must give the same Newton and Krylov counts and the same
solution to 1e-12; continued on 2 ranks (N-to-M) the solution to 1e-9.
"""

from __future__ import annotations

import json
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile
import time

import numpy as np
import pytest

from contactqvi.contact.checkpoint import DIRECTORY
from shipped_runs import COARSE, group

ROOT = pathlib.Path(__file__).resolve().parent.parent
#: The shipped case's variant that tests/shipped_runs.py runs (the uninterrupted run): its mesh and steps.
VARIANT = COARSE["cattaneo_mindlin_bodies"]
STEPS = VARIANT.steps.stop
MPIENV = {"OMPI_MCA_rmaps_base_oversubscribe": "1", "PRTE_MCA_rmaps_default_mapping_policy": ":oversubscribe",
          "OMPI_MCA_btl": "self,sm", "OMPI_ALLOW_RUN_AS_ROOT": "1", "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM": "1"}

pytestmark = pytest.mark.serial


def _command(case: pathlib.Path, out: pathlib.Path, *options: str, ranks: int = 1) -> list[str]:
    run = [sys.executable, "-m", "contactqvi", "run", str(case), "--output", str(out), "--no-plot", *options]
    return ["mpirun", "-n", str(ranks), *run] if ranks > 1 else run


def _run(command: list[str]) -> None:
    """Run ``command``; mpirun gets its own session directory: a run killed before leaves
    OpenMPI's behind, and one of a reused process id made mpirun fail ("prte_session_dir failed")."""
    session = tempfile.mkdtemp(prefix="prte-")
    try:
        done = subprocess.run(command, capture_output=True, text=True, timeout=600,
                              env=os.environ | MPIENV | {"TMPDIR": session})
    finally:
        shutil.rmtree(session, ignore_errors=True)
    assert done.returncode == 0, done.stderr[-3000:]


def _kill_during_step(case: pathlib.Path, out: pathlib.Path, step: int) -> None:
    """Start the run and kill it (SIGKILL) once step ``step`` is being solved."""
    run = subprocess.Popen(_command(case, out), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    marker = out / DIRECTORY / "checkpoint.json"
    deadline = time.monotonic() + 300.0
    while not (marker.exists() and json.loads(marker.read_text())["step"] >= step - 1):
        assert run.poll() is None and time.monotonic() < deadline
        time.sleep(0.05)
    time.sleep(0.3)  # inside step ``step``: a Newton step takes well over 0.1 s
    run.kill()
    run.wait()
    assert json.loads(marker.read_text())["step"] == step - 1, "killed outside the step meant"


def _counts(out: pathlib.Path) -> list[tuple[int, int]]:
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"].startswith("converged") and len(summary["steps"]) == STEPS
    return [(step["iterations"], step["inner_iterations"]) for step in summary["steps"]]


def _difference(a: pathlib.Path, b: pathlib.Path) -> float:
    ua, ub = (np.load(out / "solution.npz")["u"] for out in (a, b))
    return float(np.abs(ua - ub).max() / np.abs(ua).max())


@pytest.fixture(scope="module")
def killed(tmp_path_factory) -> tuple[pathlib.Path, pathlib.Path]:
    """The case file (the shipped case's coarse variant, tests/shipped_runs.py) and the output
    of its run killed during step STEPS: its checkpoint is step STEPS - 1's."""
    work = tmp_path_factory.mktemp("restart")
    text = (ROOT / "cases" / "cattaneo_mindlin_bodies.toml").read_text()
    text = text.replace('file = "../meshes/mindlin_bodies_medium.geo"', f'file = "{ROOT / "meshes" / VARIANT.mesh}"')
    head, *steps = text.split("[[steps]]")
    case = work / "case.toml"
    case.write_text("[[steps]]".join([head, *steps[:STEPS]]))
    _kill_during_step(case, work / "killed", step=STEPS)
    return case, work / "killed"


def _continued(killed: tuple[pathlib.Path, pathlib.Path], directory: pathlib.Path, ranks: int) -> pathlib.Path:
    """A copy of the killed run's output in ``directory``, continued with ``--restart`` on ``ranks``."""
    case, out = killed
    shutil.copytree(out, directory / "out")
    _run(_command(case, directory / "out", "--restart", ranks=ranks))
    return directory / "out"


@group("cattaneo_mindlin_bodies")
def test_killed_run_restarted_on_the_same_ranks_ends_as_the_uninterrupted_one(killed, shipped_runs, tmp_path):
    whole = shipped_runs["cattaneo_mindlin_bodies"]["output"]
    out = _continued(killed, tmp_path, 1)
    assert _counts(out) == _counts(whole)
    assert _difference(whole, out) <= 1e-12
    summary = json.loads((out / "summary.json").read_text())
    assert summary["restarts"] == [{"after_step": STEPS - 1, "mpi_size": 1}]
    _assert_time_steps(out)


@group("cattaneo_mindlin_bodies")
def test_killed_run_restarted_on_two_ranks(killed, shipped_runs, tmp_path):
    out = _continued(killed, tmp_path, 2)
    assert len(_counts(out)) == STEPS
    assert _difference(shipped_runs["cattaneo_mindlin_bodies"]["output"], out) <= 1e-9
    _assert_time_steps(out)


def _assert_time_steps(out: pathlib.Path) -> None:
    """Both ParaView files hold steps 1..STEPS once each (the steps after the checkpoint dropped)."""
    import adios2

    for name in ("body.bp", "contact_surface.bp"):
        with adios2.FileReader(str(out / name)) as f:
            times = [float(f.read("step", step_selection=[s, 1]).reshape(-1)[0]) for s in range(f.num_steps())]
        assert times == [float(s) for s in range(1, STEPS + 1)], (name, times)
    assert not list(out.glob(".*.previous")) and not list(out.glob(".*.partial"))


def test_a_checkpoint_of_another_case_is_a_named_error(tmp_path):
    """--restart into an output directory written for another case names the keys that differ;
    an output directory without a checkpoint has none (the run starts from step 1)."""
    from mpi4py import MPI

    from contactqvi.contact.checkpoint import read_checkpoint
    from contactqvi.parameters import ParameterError

    case = {"mesh": {"file": "block.msh"}, "material": {"young": 70e9, "poisson": 0.3}}
    assert read_checkpoint(MPI.COMM_SELF, tmp_path, case) is None
    (tmp_path / DIRECTORY).mkdir()
    marker = {"step": 2, "solved": 2, "file": "step_0002.bp", "load": 1.0, "translation": [0.0, 0.0, 0.0],
              "target": 1.0, "rotation": None, "fit": 1.0, "stride": [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
              "summary": {"case": case, "steps": [{}, {}]}}
    (tmp_path / DIRECTORY / "checkpoint.json").write_text(json.dumps(marker))
    assert read_checkpoint(MPI.COMM_SELF, tmp_path, case).step == 2
    other = {**case, "material": {"young": 200e9, "poisson": 0.3}}
    with pytest.raises(ParameterError, match=r"--restart: .*another case \(different: material\)"):
        read_checkpoint(MPI.COMM_SELF, tmp_path, other)
