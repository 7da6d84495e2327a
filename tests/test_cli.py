"""``python -m contactqvi`` from an installed (non-editable) package; PETSc options at start-up."""

from __future__ import annotations

import pathlib
import shutil
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent


@pytest.mark.serial
def test_installed_package_runs_the_demos_and_cases(tmp_path):
    venv, source = tmp_path / "venv", tmp_path / "source"  # the build writes into its source tree: a copy
    shutil.copytree(ROOT, source, ignore=shutil.ignore_patterns(".git", ".venv", "build", "results", "*.egg-info"))
    subprocess.run([sys.executable, "-m", "venv", "--system-site-packages", str(venv)], check=True)
    python = venv / "bin" / "python"
    subprocess.run([str(python), "-m", "pip", "install", "-q", "--no-build-isolation", "--no-deps", str(source)],
                   check=True, cwd=tmp_path)
    listing = subprocess.run([str(python), "-m", "contactqvi", "--help"], capture_output=True, text=True,
                             check=True, cwd=tmp_path).stdout
    assert "coulomb3d" in listing and "not installed" not in listing
    run = subprocess.run([str(python), "-m", "contactqvi", "coulomb3d", "--lev", "0", "--no-plot",
                          "--output", str(tmp_path / "out")], capture_output=True, text=True, cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    where = subprocess.run([str(python), "-c", "import contactqvi; print(contactqvi.__file__)"],
                           capture_output=True, text=True, cwd=tmp_path).stdout
    assert where.startswith(str(venv))  # the installed copy, not the source tree
    bad = subprocess.run([str(python), "-m", "contactqvi", "elasticity"], capture_output=True, text=True, cwd=tmp_path)
    assert bad.returncode == 2 and "unknown command 'elasticity'" in bad.stderr


@pytest.mark.serial
def test_log_view_through_the_petsc_pass_through(tmp_path):
    """-log_view is read by PETSc at initialisation; given on the command line it still prints at exit."""
    run = subprocess.run([sys.executable, str(ROOT / "demos" / "coulomb3d.py"), "--lev", "0", "--no-plot",
                          "--output", str(tmp_path), "-log_view"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert "PETSc Performance Summary" in run.stdout and "linear_solve" in run.stdout


class _Ranks:
    """A communicator stand-in that records MPI_Abort (its duplicate is itself)."""

    def __init__(self, size: int):
        self.size, self.rank, self.aborted = size, 0, None

    def Abort(self, code: int) -> None:
        self.aborted = code

    def Dup(self) -> _Ranks:
        return self

    def Free(self) -> None:
        pass


def _fails() -> int:
    raise RuntimeError("raised on this rank only")


def test_an_error_on_one_of_several_ranks_aborts_the_job(capsys):
    from contactqvi.cli import abort_on_error

    ranks = _Ranks(2)
    with pytest.raises(RuntimeError):  # after the (recorded) abort
        abort_on_error(_fails, ranks)
    assert ranks.aborted == 1 and "raised on this rank only" in capsys.readouterr().err


def test_an_error_on_one_rank_propagates_without_abort():
    from contactqvi.cli import abort_on_error

    ranks = _Ranks(1)
    with pytest.raises(RuntimeError, match="this rank only"):
        abort_on_error(_fails, ranks)
    assert ranks.aborted is None and abort_on_error(lambda: 3, ranks) == 3


@pytest.mark.one_rank(reason="argument parsing")
def test_log_level_in_any_case():
    """``--log-level info`` is ``INFO``; a level that is none names the choices."""
    from contactqvi.cli import make_parser

    parser = make_parser("demo", "results/demo")
    assert parser.parse_args(["--log-level", "info"]).log_level == "INFO"
    with pytest.raises(SystemExit):
        parser.parse_args(["--log-level", "loud"])
