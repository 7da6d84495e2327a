"""Test helper: the residual of (3.2a) of seed 002 for a friction problem's iterate."""

from __future__ import annotations

from petsc4py import PETSc

import numpy as np

__all__ = ["state_residual"]


def state_residual(problem, y: PETSc.Vec, lam: np.ndarray) -> float:
    """Max-norm of K y + M lambda - F over the free dofs (Dirichlet rows excluded), global."""
    work = problem.K.createVecLeft()
    problem.K.mult(y, work)
    work.axpy(-1.0, problem.F)
    values = work.array
    values[problem.boundary_dofs] += problem.boundary_mass * lam
    for bc in problem.bcs:
        dofs, first_ghost = bc.dof_indices()
        values[dofs[:first_ghost]] = 0.0
    norm = work.norm(PETSc.NormType.NORM_INFINITY)
    work.destroy()
    return float(norm)
