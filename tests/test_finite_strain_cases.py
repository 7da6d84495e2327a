"""The shipped finite-strain cases (issue 36): what each must show, and a restart that is the
same run. ``cases/rubber_pad.toml`` runs here on its coarse mesh
(``meshes/rubber_pad_coarse.geo``): the run of tests/test_shipped_cases.py."""

from __future__ import annotations

from mpi4py import MPI

import numpy as np

from contactqvi.obstacles import Cylinder
from contactqvi.runner import run_case
from shipped_runs import group, shipped_case

THICKNESS = 0.01  # m, meshes/rubber_pad.geo


@group("rubber_pad")
def test_rubber_pad_is_pressed_beyond_30_percent_and_restarts_exactly(shipped_runs, mpi_tmp_path):
    """The roller pressed 4 mm into the 10 mm pad: the top under it moves down by more than 30 %
    of the thickness, the pad's touching nodes lie on the roller (the current configuration,
    searched inside the Newton iteration) to 1e-13 m (measured 1.7e-18 m; until settled, 2e-12 m),
    every step in balance; stopped after step 4 and
    restarted, the path is the uninterrupted one to 1e-12 with the same Newton counts, and
    the restarted run draws its pictures (the forces of all eight steps among them)."""
    comm = MPI.COMM_WORLD
    case, run = shipped_case("rubber_pad"), shipped_runs["rubber_pad"]
    whole, out = run["summary"], run["output"]
    assert run["code"] == 0, whole["status"]
    assert max(step["equilibrium_error"] for step in whole["steps"]) <= 1e-9
    run_case(case, mpi_tmp_path / "parts", comm, plot=False, stop_after=4)
    parts, code = run_case(case, mpi_tmp_path / "parts", comm, plot=True, restart=True)
    assert code == 0, parts["status"]
    assert [s["iterations"] for s in parts["steps"]] == [s["iterations"] for s in whole["steps"]]
    assert parts["plot"] and parts["bodies_plot"] and parts["forces_plot"]
    if comm.rank != 0:
        return
    a, b = (np.load(path / "solution.npz") for path in (out, mpi_tmp_path / "parts"))
    assert np.abs(a["u"] - b["u"]).max() <= 1e-12 * np.abs(a["u"]).max()
    x, u = a["x"], a["u"]
    top = np.isclose(x[:, 2], 0.0)
    assert -u[top, 2].min() >= 0.3 * THICKNESS
    roller = case.obstacle.create().translated(np.asarray(case.steps[-1].translation))
    assert isinstance(roller, Cylinder)
    distance = roller.distance(x[top] + u[top])[0]
    touching = distance < 1e-6
    assert touching.sum() >= 3 and np.abs(distance[touching]).max() <= 1e-13
