"""Uzawa's algorithm for (P*), the first-order baseline of Sect. 6 of seed 002.

lambda^(l+1) = P(lambda^l + gamma tau_f y^l) with y^l solving (2.3) for lambda^l
and P the nodal projection onto [-g, g]: the explicit counterpart of (ALM) (5.24).
It converges only for gamma in an unknown interval [alpha_1, alpha_2].
"""

from __future__ import annotations

import dataclasses
import logging
import typing

from petsc4py import PETSc

import numpy as np

from dolfinx import fem

from contactqvi.friction.pdas import DEFAULT_KSP_OPTIONS
from contactqvi.friction.problem import FrictionProblem
from contactqvi.linalg import create_ksp, ksp_converged_reason
from contactqvi.parameters import require, require_positive

__all__ = ["UzawaResult", "uzawa"]

logger = logging.getLogger(__name__)

#: ``monitor(l, y, lam)``: observer of the iterates of :func:`uzawa` (y = y^(l-1), lam = lambda^l).
Monitor = typing.Callable[[int, fem.Function, PETSc.Vec], None]


@dataclasses.dataclass
class UzawaResult:
    """Outcome of the Uzawa iteration.

    Attributes:
        y: the last primal iterate, the state (2.3) of the last-but-one multiplier.
        lam: the last multiplier (nodal boundary PETSc Vec).
        status: ``converged`` or ``max_iterations``.
        iterations: number of linear solves (one per iteration).
        history: per iteration d_lambda (6.1) if a reference is given and
            ||lambda^(l+1) - lambda^l||_{L2(Gamma_f)}.
    """

    y: fem.Function
    lam: PETSc.Vec
    status: str
    iterations: int
    history: list[dict[str, typing.Any]]

    @property
    def converged(self) -> bool:
        """True if the stopping tolerance was met."""
        return self.status == "converged"


def uzawa(
    problem: FrictionProblem,
    gamma: float,
    lam0: PETSc.Vec | None = None,
    reference: PETSc.Vec | None = None,
    tol: float = 1e-4,
    max_iterations: int = 1000,
    prefix: str = "uzawa_",
    monitor: Monitor | None = None,
) -> UzawaResult:
    """Uzawa's method for (P*) with step gamma, lambda^0 = 0 by default (Sect. 6).

    Args:
        problem: the discrete friction problem.
        gamma: the step length gamma > 0.
        lam0: initial multiplier.
        reference: lambda_bar; if given the iteration stops when d_lambda^l < tol
            (the paper's criterion), otherwise when ||lambda^(l+1) - lambda^l|| < tol.
        tol: stopping tolerance.
        max_iterations: maximal number of iterations (linear solves).
        prefix: PETSc options prefix of the linear solver (K is factorised once).
        monitor: called as ``monitor(l, y, lam)`` after every iteration with the
            state y of lambda^(l-1) and the new lambda^l; must not modify them.
    """
    require_positive("gamma", gamma)
    require_positive("tol", tol)
    require(
        isinstance(max_iterations, (int, np.integer)) and max_iterations >= 1,
        "max_iterations",
        f"must be an integer >= 1, got {max_iterations!r}",
    )
    ksp = create_ksp(problem.comm, prefix, DEFAULT_KSP_OPTIONS, problem.K)
    rhs = problem.K.createVecLeft()
    lam = problem.create_boundary_vector() if lam0 is None else lam0.copy()
    y = fem.Function(problem.V, name="y")
    history: list[dict[str, typing.Any]] = []
    status = "max_iterations"
    try:
        for iteration in range(1, max_iterations + 1):
            problem.F.copy(rhs)
            rhs.array[problem.boundary_dofs] -= problem.boundary_mass * lam.array_r
            ksp.solve(rhs, y.x.petsc_vec)
            if ksp.getConvergedReason() <= 0:
                raise RuntimeError(f"linear solve failed: {ksp_converged_reason(ksp)}")
            y.x.scatter_forward()
            new = np.clip(lam.array_r + gamma * problem.trace(y.x.petsc_vec), -problem.g, problem.g)
            change = problem.boundary_norm(new - lam.array_r)
            lam.array[:] = new
            d_lambda = problem.boundary_norm(reference.array_r - new) if reference is not None else None
            history.append({"l": iteration, "d_lambda": d_lambda, "lambda_change": change})
            if monitor is not None:
                monitor(iteration, y, lam)
            logger.info(
                "  Uzawa l=%4d |lambda^l - lambda^(l-1)|=%.3e%s",
                iteration, change, "" if d_lambda is None else f" d_lambda={d_lambda:.3e}",
            )  # fmt: skip
            if (d_lambda if d_lambda is not None else change) < tol:
                status = "converged"
                break
    finally:
        ksp.destroy()
        rhs.destroy()
    return UzawaResult(y=y, lam=lam, status=status, iterations=len(history), history=history)
