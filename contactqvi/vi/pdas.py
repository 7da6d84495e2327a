"""Primal-dual active set method (Hintermueller-Ito-Kunisch) on the nodal obstacle.

Used after PFMY as feasibility restoration (Sect. 4.1 of seed 003): for the
discrete problem  A u + lambda = b,  u <= theta,  lambda >= 0,
lambda (theta - u) = 0, iterate
  active = {lambda + c (u - theta) > 0},
  solve A u = b on the inactive rows with u = theta on the active rows,
  lambda = b - A u (the residual at the new iterate) on the active set, 0 elsewhere,
until the active set repeats; finally u = min(u, theta) nodewise, so the active
set is read off exactly from u == theta.

The reduced matrix is one work matrix with the sparsity of A: each iteration
copies A's values into it and zeroes the active rows and columns while keeping
the pattern, so the direct solver's symbolic analysis is done once.
"""

from __future__ import annotations

import dataclasses

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

from contactqvi.lifetime import PETScOwner
from contactqvi.linalg import create_ksp, preset
from contactqvi.result import Result, Status
from contactqvi.vi.problem import ObstacleProblem

__all__ = ["PDASResult", "ObstacleActiveSetSolver"]


@dataclasses.dataclass(kw_only=True)
class PDASResult(Result):
    """``iterations`` are linear solves; ``active_sizes`` the active-set size of each."""

    active_sizes: list[int] = dataclasses.field(default_factory=list)


class ObstacleActiveSetSolver(PETScOwner):
    """PDAS for the nodal obstacle; the iterate is ``problem.u``, the multiplier ``problem.multiplier``.

    Args:
        problem: the obstacle problem.
        max_iterations: at most this many linear solves.
        c: the PDAS constant is ``c`` times the stiffness diagonal (node-wise scaling).
        prefix: PETSc options prefix of the KSP.
        ksp: KSP preset of the reduced systems.
    """

    def __init__(
        self,
        problem: ObstacleProblem,
        max_iterations: int = 100,
        c: float = 1.0,
        prefix: str = "obstacle_pdas_",
        ksp: str = "lu",
    ):
        self.problem, self.max_iterations = problem, max_iterations
        self.ksp = create_ksp(problem.comm, prefix, preset(ksp, "ksp"))
        self.c = problem.A.getDiagonal()
        self.c.scale(c)
        self.rhs = problem.load.duplicate()
        self.reduced = problem.A.duplicate(copy=True)
        self.reduced.setOption(PETSc.Mat.Option.KEEP_NONZERO_PATTERN, True)
        self.ksp.setOperators(self.reduced)
        self.offset = problem.V.dofmap.index_map.local_range[0]

    def petsc_objects(self) -> list[PETSc.Object]:
        return [self.ksp, self.c, self.rhs, self.reduced]

    def _active(self) -> np.ndarray:
        """{lambda + c (u - theta) > 0} on the owned free nodes."""
        p = self.problem
        x, theta = p.u.x.petsc_vec.array_r, p.obstacle.x.petsc_vec.array_r
        return p.free & (p.multiplier.array_r + self.c.array_r * (x - theta) > 0)

    def _solve_reduced(self, b: PETSc.Vec, active: np.ndarray) -> bool:
        """u = theta on ``active``, A u = b on the other rows; False if the linear solve failed."""
        p = self.problem
        p.A.copy(self.reduced, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        b.copy(self.rhs)
        rows_glob = (np.flatnonzero(active) + self.offset).astype(PETSc.IntType)
        self.reduced.zeroRowsColumns(rows_glob, 1.0, p.obstacle.x.petsc_vec, self.rhs)
        self.ksp.solve(self.rhs, p.u.x.petsc_vec)
        p.u.x.scatter_forward()
        return self.ksp.getConvergedReason() > 0

    def solve(self) -> PDASResult:
        """Restore feasibility starting from ``problem.u`` (e.g. the last PFMY iterate)."""
        p = self.problem
        comm, lam = p.comm, p.multiplier
        b = p.assemble_load()
        p.residual(p.u, lam)
        result = PDASResult(status=Status.DIVERGED_MAX_IT, iterations=0)
        previous = None
        for _ in range(self.max_iterations + 1):
            active = self._active()
            changed = p.n_owned if previous is None else int(np.count_nonzero(active != previous))
            if comm.allreduce(changed, op=MPI.SUM) == 0:
                result.status = Status.CONVERGED_ACTIVE_SET
                break
            if result.iterations == self.max_iterations:
                break
            previous = active
            result.active_sizes.append(comm.allreduce(int(np.count_nonzero(active)), op=MPI.SUM))
            result.iterations += 1
            with result.timings.phase("linear_solve"):
                solved = self._solve_reduced(b, active)
            result.inner_iterations += self.ksp.getIterationNumber()
            if not solved:
                result.status = Status.DIVERGED_LINEAR_SOLVE
                break
            p.residual(p.u, lam)
            lam.array[~active] = 0.0
        self._project()
        return result

    def _project(self) -> None:
        """Exact projection: active nodes become exactly theta, the active set is {u == theta}."""
        p = self.problem
        x, theta, n = p.u.x.petsc_vec, p.obstacle.x.petsc_vec, p.n_owned
        x.array[:n] = np.minimum(x.array[:n], theta.array[:n])
        p.u.x.scatter_forward()
        p.residual(p.u, p.multiplier)
        p.multiplier.array[x.array[:n] < theta.array[:n]] = 0.0
