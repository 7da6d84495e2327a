"""1 vs N MPI ranks: same iteration counts, statuses and solutions (seed 002 solvers, all discretisations)."""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi import tables
from contactqvi.friction import (
    FrictionActiveSetSolver,
    UzawaSolver,
    augmented_lagrangian,
    create_problem,
    semismooth_newton_sigma,
)
from contactqvi.friction.output import boundary_function
from contactqvi.problems.stadler import stadler_example


def _gathered(problem, result) -> tuple:
    """y at all vertices and lambda on Gamma_f, gathered on rank 0 and sorted by coordinates (None elsewhere)."""
    _, y = tables.gather_vertex_values(result.y)
    _, lam = tables.gather_vertex_values(boundary_function(problem, result.lam, "lambda"))
    return y, lam


def _run_all(comm: MPI.Comm, example: int, discretisation: str) -> dict:
    problem = create_problem(comm, stadler_example(example), N=21, discretisation=discretisation)
    out = {}
    with problem, FrictionActiveSetSolver(problem) as pdas, UzawaSolver(problem) as uzawa:
        reference = pdas.solve(gamma=1e16)
        out["reference"] = ((reference.iterations, str(reference.status)), *_gathered(problem, reference))
        runs = {
            "pdas": lambda: pdas.solve(gamma=1e3, sigma=1.0, reference=reference.lam),
            "ss": lambda: pdas.solve(gamma=50.0, sigma=semismooth_newton_sigma(50.0)),
            "alm": lambda: augmented_lagrangian(pdas, schedule="power10", inner="inexact", max_outer=4),
            "uzawa": lambda: uzawa.solve(gamma=0.2, max_iterations=15, atol=1e-12),
        }
        for name, run in runs.items():
            result = run()
            counts = [h.get("inner_iterations", h.get("A_plus")) for h in result.history]
            out[name] = ((result.iterations, counts, str(result.status)), *_gathered(problem, result))
    return out


@pytest.mark.parametrize("example, discretisation", [(1, "q1"), (2, "p1"), (3, "q1"), (2, "fd")])
def test_parallel_equals_serial(example, discretisation):
    world = MPI.COMM_WORLD
    serial = _run_all(MPI.COMM_SELF, example, discretisation)
    parallel = _run_all(world, example, discretisation)
    failures = []
    if world.rank == 0:
        for name, (info_s, y_s, lam_s) in serial.items():
            info_p, y_p, lam_p = parallel[name]
            if info_s != info_p:
                failures.append(f"{name}: iterations {info_s} (1 rank) vs {info_p} ({world.size} ranks)")
            dy, dl = float(np.abs(y_s - y_p).max()), float(np.abs(lam_s - lam_p).max())
            if dy > 1e-10 or dl > 1e-10:
                failures.append(f"{name}: |y_1 - y_n| = {dy:.2e}, |lambda_1 - lambda_n| = {dl:.2e}")
    failures = world.bcast(failures, root=0)
    assert not failures, "; ".join(failures)
