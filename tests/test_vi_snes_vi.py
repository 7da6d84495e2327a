"""The SNES-VI wrapper on a problem with a closed-form solution, and SNES reasons as Status."""

from __future__ import annotations

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import pytest

from contactqvi.result import Status
from contactqvi.vi import AffineProblem, SNESVariationalInequality, snes_status


def _diagonal_problem(n_local: int = 6):
    """A = diag(d), l: the VI  A x - l = 0 on lower <= x <= upper is solved by clip(l / d, lower, upper)."""
    comm = MPI.COMM_WORLD
    A = PETSc.Mat().createAIJ(((n_local, None), (n_local, None)), nnz=(1, 0), comm=comm)
    start = A.getOwnershipRange()[0]
    rows = np.arange(start, start + n_local, dtype=PETSc.IntType)
    d = 1.0 + rows % 3
    for row, value in zip(rows, d):
        A.setValue(row, row, value)
    A.assemble()
    load = A.createVecLeft()
    load.array[:] = np.sin(rows + 1.0) * 3.0
    return A, load, d


@pytest.mark.parametrize("ksp", ["lu", "cg_jacobi"])
def test_box_constrained_solution_is_the_clipped_one(ksp):
    A, load, d = _diagonal_problem()
    x = A.createVecRight()
    with AffineProblem(A, load) as problem, SNESVariationalInequality(problem, f"tvi_{ksp}_", ksp, {"snes_rtol": 1e-12}) as vi:
        vi.lower.set(-1.0)
        vi.upper.array[::2] = 0.5  # every other unknown bounded above, the rest not
        result = vi.solve(x)
        expected = np.clip(load.array / d, -1.0, vi.upper.array)
    assert result.converged and result.status > 0 and result.reason.startswith("CONVERGED")
    assert result.iterations >= 1 and result.inner_iterations >= result.iterations
    assert result.timings["solve"] >= 0.0
    error = MPI.COMM_WORLD.allreduce(float(np.max(np.abs(x.array - expected))), op=MPI.MAX)
    assert error < 1e-12
    for obj in (x, load, A):
        obj.destroy()


def test_failure_is_a_negative_status():
    A, load, _ = _diagonal_problem()
    x = A.createVecRight()
    with AffineProblem(A, load) as problem, SNESVariationalInequality(problem, "tvi_fail_", "cg_jacobi",
                                                                      {"snes_max_it": 0, "snes_rtol": 1e-12}) as vi:
        result = vi.solve(x)
        assert snes_status(vi.snes) == result.status
    assert result.status == Status.DIVERGED_MAX_IT and not result.converged
    assert result.reason == "DIVERGED_MAX_IT"
    for obj in (x, load, A):
        obj.destroy()
