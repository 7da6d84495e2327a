"""The forces of a load path as a table and a picture (``forces.csv``, ``forces.png``):
the summary's numbers, one row per converged step, against what drives the path."""

from __future__ import annotations

import csv

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi.contact.figures import plot_forces
from contactqvi.contact.force_history import force_columns
from shipped_runs import group


@group("sliding_blocks")
def test_forces_of_the_sliding_blocks_path(shipped_runs):
    """cases/sliding_blocks.toml: forces.csv holds, per step, exactly the summary's load,
    translation, pair forces and reactions (floats written exactly), and forces.png is drawn
    against the slide (x translation)."""
    run = shipped_runs["sliding_blocks"]
    summary, out = run["summary"], run["output"]
    assert run["code"] == 0, summary["status"]
    assert plot_forces(out / "forces.png", summary["steps"], MPI.COMM_WORLD) is True
    if MPI.COMM_WORLD.rank != 0:
        return
    assert (out / "forces.png").stat().st_size > 10_000
    with open(out / "forces.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == len(summary["steps"])
    for row, step in zip(rows, summary["steps"]):
        assert float(row["step"]) == step["step"] and float(row["load"]) == step["load"]
        assert [float(row[f"translation_{a}"]) for a in "xyz"] == step["translation"]
        for name, force in step["pair_forces"].items():
            assert [float(row[f"{name} F_{a} [N]"]) for a in "xyz"] == force
        for name, force in step["reaction_forces"].items():
            assert [float(row[f"{name} R_{a} [N]"]) for a in "xyz"] == force


@pytest.mark.one_rank(reason="columns of a summary's steps (lists of numbers), no mesh")
def test_force_columns_leave_out_failed_steps():
    steps = [{"step": 1, "load": 0.5, "converged": True, "translation": [0.0, 0.0, 0.0],
              "pair_forces": {"a/b": [0.0, 0.0, 1.0]}, "reaction_forces": {"a.top": [0.0, 0.0, -1.0]}},
             {"step": 2, "load": 1.0, "converged": False},
             {"step": 2, "load": 1.0, "converged": True, "translation": [0.1, 0.0, 0.0],
              "pair_forces": {"a/b": [-0.2, 0.0, 1.0]}, "reaction_forces": {"a.top": [0.2, 0.0, -1.0]}}]
    columns = force_columns(steps)
    assert columns["step"].tolist() == [1.0, 2.0]
    assert columns["translation_x"].tolist() == [0.0, 0.1]
    assert columns["a/b F_x [N]"].tolist() == [0.0, -0.2]
    assert columns["a.top R_z [N]"].tolist() == [-1.0, -1.0]
    assert np.all(np.isfinite(np.column_stack(list(columns.values()))))


@pytest.mark.one_rank(reason="columns of a summary's steps (lists of numbers), no mesh")
def test_a_torque_path_is_plotted_against_its_rotation():
    """A path that only turns its moved groups (a torque path) has the rotation angle as abscissa;
    a path that translates them keeps the translation, one that does neither the load factor."""
    from contactqvi.contact.force_history import _abscissa

    def step(k: int, angle: float | None, x: float = 0.0) -> dict:
        entry = {"step": k, "load": 1.0, "converged": True, "translation": [x, 0.0, 0.0],
                 "pair_forces": {"a/b": [0.0, 0.0, 1.0]}}
        return entry if angle is None else {**entry, "rotation": {"axis": [0, 0, 1], "angle": angle}}

    columns = force_columns([step(1, None), step(2, 0.02), step(3, 0.1)])
    assert columns["rotation_angle"].tolist() == [0.0, 0.02, 0.1]
    values, label = _abscissa(columns)
    assert values.tolist() == [0.0, 0.02, 0.1] and label.startswith("rotation")
    assert _abscissa(force_columns([step(1, 0.1, 0.0), step(2, 0.2, 0.5)]))[1].startswith("translation")
    assert _abscissa(force_columns([step(1, None), step(2, None)]))[1] == "load factor"
