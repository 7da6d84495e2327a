"""Diagnostics of the seed-002 solvers: the paper's iteration counts, spectra of C_h, symmetry defects.

Used by ``benchmarks/stadler_tables.py`` and the tests; every function is collective
over the problem's communicator and gives the same value on every rank.
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np

from contactqvi.friction.pdas import ActiveSetResult
from contactqvi.friction.problem import FrictionProblem
from contactqvi.linalg import create_ksp, preset
from contactqvi.parameters import require
from contactqvi.result import Status

__all__ = ["iteration_count", "set_changes", "neumann_to_dirichlet_eigenvalue", "mirror_x1"]


def iteration_count(result: ActiveSetResult) -> int | str:
    """The paper's count: (PDAS) iterations if the sets repeated, else ``div (<status> after <n>)``."""
    if result.status == Status.CONVERGED_ACTIVE_SET:
        return result.iterations
    return f"div ({result.status} after {result.iterations})"


def set_changes(result: ActiveSetResult) -> list[int]:
    """Nodes changing set in iteration 2, 3, ... of a (PDAS) run."""
    return [h["changes"] for h in result.history[1:]]


def neumann_to_dirichlet_eigenvalue(
    problem: FrictionProblem, mask: np.ndarray, shift: float = 0.0, iterations: int = 400, seed: int = 2004
) -> float:
    """Eigenvalue of C_h = tau K^-1 tau^* M restricted to ``mask`` farthest from ``shift`` (power iteration).

    C_h is the discrete Neumann-to-Dirichlet map (4.2), self-adjoint and positive
    definite in the lumped L2(Gamma_f) product (for a symmetric K). Power iteration
    on C_h - shift I gives lambda_max for shift = 0 and lambda_min for shift =
    lambda_max. Uzawa with frozen sets is Richardson's iteration for C_h on the
    inactive set: the error contracts by max |1 - gamma lambda| over its spectrum,
    which is < 1 iff gamma < 2 / lambda_max, and is 1 - gamma lambda_min at best
    for small gamma. K is factorised once (``lu`` preset, prefix ``friction_ntd_``).
    """
    ksp = create_ksp(problem.comm, "friction_ntd_", preset("lu"), problem.K)
    rhs, y = problem.K.createVecLeft(), problem.K.createVecLeft()
    v = np.where(mask, np.random.default_rng(seed=seed).uniform(0.5, 1.5, mask.size), 0.0)
    estimate = 0.0
    for _ in range(iterations):
        v /= problem.boundary_norm(v)
        rhs.set(0.0)
        rhs.array[problem.boundary_dofs] = problem.boundary_mass * v
        ksp.solve(rhs, y)
        w = np.where(mask, problem.trace(y) - shift * v, 0.0)
        estimate = shift + problem.comm.allreduce(float(np.dot(problem.boundary_mass * w, v)), op=MPI.SUM)
        v = w
    for obj in (ksp, rhs, y):
        obj.destroy()
    return estimate


def mirror_x1(comm: MPI.Comm, x: np.ndarray, values: np.ndarray) -> np.ndarray:
    """v(1 - x1, x2) at this rank's nodes ``x`` (n, >= 2), from the values ``v`` of all ranks.

    The node set (all ranks together) must be symmetric about x1 = 1/2, as the grid
    points of the unit square are. Example 1's data are odd about x1 = 1/2, and so
    are lambda_bar and every Uzawa iterate in exact arithmetic: ``v + mirror_x1(...)``
    measures how far round-off has broken that symmetry.
    """
    scale = 1e9  # coordinates in [0, 1], carrying round-off of about 1e-16

    def key(x1: np.ndarray, x2: np.ndarray) -> np.ndarray:
        return np.rint(x1 * scale).astype(np.int64) * (int(scale) + 1) + np.rint(x2 * scale).astype(np.int64)

    keys = np.concatenate(comm.allgather(key(x[:, 0], x[:, 1])))
    all_values = np.concatenate(comm.allgather(np.asarray(values, dtype=float)))
    order = np.argsort(keys)
    wanted = key(1.0 - x[:, 0], x[:, 1])
    position = np.minimum(np.searchsorted(keys[order], wanted), len(keys) - 1)
    found = comm.allreduce(bool(np.all(keys[order][position] == wanted)), op=MPI.LAND)
    require(found, "x", "the node set is not symmetric about x1 = 1/2")
    return all_values[order][position]
