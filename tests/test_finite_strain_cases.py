"""The shipped finite-strain cases (issue 36): what each must show, and a restart that is the
same run. ``cases/rubber_pad.toml`` runs here on its coarse mesh
(``meshes/rubber_pad_coarse.geo``, as in tests/test_shipped_cases.py)."""

from __future__ import annotations

import dataclasses
import pathlib

from mpi4py import MPI

import numpy as np

from contactqvi.case import load_case
from contactqvi.obstacles import Cylinder
from contactqvi.runner import run_case

ROOT = pathlib.Path(__file__).resolve().parent.parent
THICKNESS = 0.01  # m, meshes/rubber_pad.geo


def _rubber_pad():
    case = load_case(ROOT / "cases" / "rubber_pad.toml")
    return dataclasses.replace(case, mesh=dataclasses.replace(case.mesh, file=ROOT / "meshes" / "rubber_pad_coarse.geo"))


def test_rubber_pad_is_pressed_beyond_30_percent_and_restarts_exactly(mpi_tmp_path):
    """The roller pressed 4 mm into the 10 mm pad: the top under it moves down by more than 30 %
    of the thickness, the pad's touching nodes lie on the roller (the current configuration,
    searched until settled) to 1e-7 m, every step in balance; stopped after step 4 and
    restarted, the path is the uninterrupted one to 1e-12 with the same Newton counts."""
    comm = MPI.COMM_WORLD
    case = _rubber_pad()
    whole, code = run_case(case, mpi_tmp_path / "whole", comm, plot=False)
    assert code == 0, whole["status"]
    assert max(step["equilibrium_error"] for step in whole["steps"]) <= 1e-9
    run_case(case, mpi_tmp_path / "parts", comm, plot=False, stop_after=4)
    parts, code = run_case(case, mpi_tmp_path / "parts", comm, plot=False, restart=True)
    assert code == 0, parts["status"]
    assert [s["iterations"] for s in parts["steps"]] == [s["iterations"] for s in whole["steps"]]
    if comm.rank != 0:
        return
    a, b = (np.load(mpi_tmp_path / name / "solution.npz") for name in ("whole", "parts"))
    assert np.abs(a["u"] - b["u"]).max() <= 1e-12 * np.abs(a["u"]).max()
    x, u = a["x"], a["u"]
    top = np.isclose(x[:, 2], 0.0)
    assert -u[top, 2].min() >= 0.3 * THICKNESS
    roller = case.obstacle.create().translated(np.asarray(case.steps[-1].translation))
    assert isinstance(roller, Cylinder)
    distance = roller.distance(x[top] + u[top])[0]
    touching = distance < 1e-6
    assert touching.sum() >= 3 and np.abs(distance[touching]).max() <= 1e-7
