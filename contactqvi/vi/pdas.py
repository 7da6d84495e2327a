"""Primal-dual active set method (Hintermueller-Ito-Kunisch) on the nodal obstacle.

Used after PFMY as feasibility restoration (Sect. 4.1 of seed 003): for the
discrete problem  A u + lambda = b,  u <= theta,  lambda >= 0,
lambda (theta - u) = 0, iterate
  active = {lambda + c (u - theta) > 0},
  solve A u = b on the inactive rows with u = theta on the active rows,
  lambda = b - A u (the residual at the new iterate) on the active set, 0 elsewhere,
until the active set repeats; finally u = min(u, theta) nodewise, so the active
set is read off exactly from u == theta.
"""

from __future__ import annotations

import dataclasses

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

from contactqvi.linalg import create_ksp, ksp_converged_reason
from contactqvi.vi.problem import ObstacleProblem

__all__ = ["PDASResult", "PrimalDualActiveSet", "DEFAULT_KSP_OPTIONS"]

DEFAULT_KSP_OPTIONS = {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}


@dataclasses.dataclass
class PDASResult:
    """Iterations (linear solves), active-set sizes per iteration, convergence flag."""

    iterations: int
    active_sizes: list[int]
    converged: bool


class PrimalDualActiveSet:
    """PDAS for the nodal obstacle; the iterate is ``problem.u``, the multiplier ``problem.multiplier``.

    Args:
        problem: the obstacle problem.
        max_iterations: at most this many linear solves.
        c: the PDAS constant is ``c`` times the stiffness diagonal (node-wise scaling).
        prefix: PETSc options prefix of the KSP.
    """

    def __init__(self, problem: ObstacleProblem, max_iterations: int = 100, c: float = 1.0, prefix: str = "obstacle_pdas_"):
        self.problem, self.max_iterations = problem, max_iterations
        self.ksp = create_ksp(problem.comm, prefix, DEFAULT_KSP_OPTIONS)
        self.c = problem.A.getDiagonal()
        self.c.scale(c)
        self.rhs = problem.load.duplicate()
        self.offset = problem.V.dofmap.index_map.local_range[0]

    def solve(self) -> PDASResult:
        """Restore feasibility starting from ``problem.u`` (e.g. the last PFMY iterate)."""
        p = self.problem
        comm, n = p.comm, p.n_owned
        x, lam = p.u.x.petsc_vec, p.multiplier
        b = p.assemble_load()
        theta = p.obstacle.x.petsc_vec
        p.residual(p.u, lam)
        previous = None
        sizes: list[int] = []
        converged = False
        A_work = None
        for _ in range(self.max_iterations + 1):
            active = p.free & (lam.array + self.c.array * (x.array - theta.array) > 0)
            changed = n if previous is None else int(np.count_nonzero(active != previous))
            if comm.allreduce(changed, op=MPI.SUM) == 0:
                converged = True
                break
            if len(sizes) == self.max_iterations:
                break
            previous = active
            sizes.append(comm.allreduce(int(np.count_nonzero(active)), op=MPI.SUM))
            if A_work is not None:
                A_work.destroy()
            A_work = p.A.duplicate(copy=True)
            b.copy(self.rhs)
            rows_glob = (np.flatnonzero(active) + self.offset).astype(PETSc.IntType)
            A_work.zeroRowsColumns(rows_glob, 1.0, theta, self.rhs)
            self.ksp.setOperators(A_work)
            self.ksp.solve(self.rhs, x)
            if self.ksp.getConvergedReason() <= 0:
                raise RuntimeError(f"PDAS: linear solve failed ({ksp_converged_reason(self.ksp)})")
            p.u.x.scatter_forward()
            p.residual(p.u, lam)
            lam.array[~active] = 0.0
        if A_work is not None:
            A_work.destroy()
        # Exact projection: active nodes become exactly theta, the active set is {u == theta}.
        x.array[:n] = np.minimum(x.array[:n], theta.array[:n])
        p.u.x.scatter_forward()
        p.residual(p.u, lam)
        lam.array[x.array[:n] < theta.array[:n]] = 0.0
        return PDASResult(len(sizes), sizes, converged)

    def destroy(self) -> None:
        for obj in (self.ksp, self.c, self.rhs):
            obj.destroy()
