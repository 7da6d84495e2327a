"""1 vs N MPI ranks: same iteration counts and the same solutions (seed 002 solvers)."""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest

from contactqvi.friction import PrimalDualActiveSet, augmented_lagrangian, semismooth_newton_sigma, uzawa
from contactqvi.problems.stadler import create_stadler_problem, stadler_example


def _gather_sorted(comm: MPI.Comm, x: np.ndarray, values: np.ndarray):
    """Values gathered on rank 0 and sorted by coordinates rounded to 1e-12.

    (tabulate_dof_coordinates carries round-off that may differ between
    partitions, so exact coordinates are no reliable sort key.)
    """
    xs, vs = comm.gather(x, root=0), comm.gather(values.copy(), root=0)
    if comm.rank != 0:
        return None
    x, values = np.round(np.vstack(xs), 12) + 0.0, np.concatenate(vs)
    return values[np.lexsort((x[:, 0], x[:, 1]))]


def _gather_y(problem, y):
    n_owned = problem.V.dofmap.index_map.size_local
    return _gather_sorted(problem.comm, problem.V.tabulate_dof_coordinates()[:n_owned], y.x.array[:n_owned])


def _gather_boundary(problem, lam):
    """Friction-node lambda gathered on rank 0, sorted by coordinates."""
    return _gather_sorted(problem.comm, problem.V.tabulate_dof_coordinates()[problem.boundary_dofs], lam.array_r)


def _run_all(comm: MPI.Comm, example: int, cell_type: str) -> dict:
    problem = create_stadler_problem(comm, stadler_example(example), 21, cell_type)
    pdas = PrimalDualActiveSet(problem)
    reference = pdas.solve(1e16)
    runs = {
        "pdas": pdas.solve(1e3, 1.0, reference=reference.lam),
        "ss": pdas.solve(50.0, semismooth_newton_sigma(50.0)),
        "alm": augmented_lagrangian(pdas, lambda step: 10.0**step, inner="inexact", max_outer=4),
        "uzawa": uzawa(problem, 0.2, max_iterations=15, tol=1e-12),
    }
    out = {
        "reference": (reference.iterations, _gather_y(problem, reference.y), _gather_boundary(problem, reference.lam))
    }
    for name, result in runs.items():
        counts = [h.get("inner_iterations", h.get("A_plus")) for h in result.history]
        iterations = getattr(result, "iterations", None) or getattr(result, "outer_iterations", None)
        info = (iterations, counts, result.status)
        out[name] = (info, _gather_y(problem, result.y), _gather_boundary(problem, result.lam))
    return out


@pytest.mark.parametrize("example, cell_type", [(1, "quadrilateral"), (2, "triangle"), (3, "quadrilateral")])
def test_parallel_equals_serial(example, cell_type):
    world = MPI.COMM_WORLD
    serial = _run_all(MPI.COMM_SELF, example, cell_type)
    parallel = _run_all(world, example, cell_type)
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
