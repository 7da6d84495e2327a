"""Coulomb friction as the fixed point of Tresca problems: the classical method.

The literature's way to Coulomb friction (seed 000, refs. [2, 3]): given the
normal forces lambda^(j) of the previous iterate, solve the Tresca problem with
the slip bound s = F lambda^(j) (a VI of the second kind) and repeat,
    s^(j+1) = F lambda(u^(j)),   u^(j+1) = Tresca solution for s^(j+1), started from u^(j).
The same holds for any law whose bound b(lambda) depends on the normal force
(s^(j+1) = b(lambda(u^(j))), e.g. a pressure-dependent coefficient).
Each Tresca problem is solved by the same SCD semismooth* Newton method
(:class:`~contactqvi.contact.scd_newton.SCDNewtonSolver` with a
:class:`~contactqvi.laws.LinearSlipBound` of given bound). The Tresca solves
are inexact: each stops when its own residual is below ``forcing`` times the
current Coulomb residual (or the final target), which keeps the outer iteration
convergent while not over-solving early Tresca problems. The method stops on
the Coulomb residual ||y^|| of (6.17) with the test of the SCD Newton method
(:meth:`~contactqvi.contact.scd_newton.SCDNewtonSolver.solve`), so both reach the
same accuracy.
"""

from __future__ import annotations

import dataclasses
import logging

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

from contactqvi.contact.problem import ContactProblem
from contactqvi.contact.scd_newton import PARAMETERS, SCDNewtonSolver
from contactqvi.laws import LinearSlipBound
from contactqvi.parameters import require
from contactqvi.result import Result, Status

__all__ = ["FORCING", "TrescaFixedPointResult", "solve_tresca_fixed_point"]

logger = logging.getLogger(__name__)

#: Inner tolerance factor of the Tresca solves (``forcing``). Measured (benchmarks/coulomb_peers.py,
#: lev 6 and 7, all six cases, 1 rank, CPU time of the six solves at lev 7): 1e-1 49 s, 3e-2 59 s,
#: 1e-2 61 s, 1e-3 74 s; 3e-1 and 5e-1 are no faster. Looser Tresca solves cost more Tresca
#: problems but fewer Newton steps in all.
FORCING = 1e-1


@dataclasses.dataclass(kw_only=True)
class TrescaFixedPointResult(Result):
    """Outcome of :func:`solve_tresca_fixed_point`: ``iterations`` counts Tresca problems,
    ``inner_iterations`` Krylov iterations over all of them.

    Attributes:
        newton_iterations: SCD Newton steps over all Tresca solves.
    """

    newton_iterations: int = 0


def solve_tresca_fixed_point(
    problem: ContactProblem,
    u: PETSc.Vec,
    parameters: dict | None = None,
    max_iterations: int = 50,
    forcing: float = FORCING,
    prefix: str = "tresca_",
) -> TrescaFixedPointResult:
    """Solve the Coulomb problem ``problem`` by fixed-point iteration on the slip bound, in place.

    One :class:`SCDNewtonSolver` solves every Tresca problem (its gamma, matrices and
    Krylov solver are kept; the slip bound of its law is updated in place). It also
    measures the Coulomb residual: the normal part theta of the graph point (6.17)
    does not depend on the slip bound, so with the bound b(lambda(u)) of the problem's
    law the Tresca point at u is the Coulomb point at u.

    Args:
        problem: contact problem whose law's bound depends on the normal force
            (Coulomb with F > 0: ``problem.law.slope_bound`` > 0).
        u: initial guess (shifted displacements), overwritten by the solution.
        parameters: SCD Newton parameters of the Tresca solves; ``rtol``, ``floor`` and
            ``atol`` are the final accuracy of the Coulomb residual.
        max_iterations: Tresca problems before giving up (status ``DIVERGED_MAX_IT``).
        forcing: each Tresca solve stops at ``forcing`` times the Coulomb residual
            at its start (and never below the final target).
        prefix: PETSc options prefix of the Newton-step KSP of the Tresca solves.
    """
    p = PARAMETERS.check(parameters)
    _check_arguments(problem, forcing, max_iterations)
    law = problem.law
    result = TrescaFixedPointResult(status=Status.DIVERGED_MAX_IT, iterations=0)
    slip_bound = np.zeros(len(problem.contact_blk))  # b(lambda(u)) of the current iterate, written in place
    tresca = dataclasses.replace(problem, law=LinearSlipBound(given=slip_bound))
    with result.timings.phase("solve"), SCDNewtonSolver(tresca, p, prefix=prefix) as solver:
        slip_bound[:] = law.bound(-solver.residual(u).z[:, 2])  # theta does not depend on s
        norm = norm0 = solver.residual(u).norm  # of the Coulomb graph point (6.17) at u
        target = max(p["rtol"] * norm0, p["floor"] * problem.force_scale(), p["atol"])
        for j in range(max_iterations + 1):
            entry = {"j": j, "residual": norm, "relative_residual": norm / norm0 if norm0 else 0.0}
            result.history.append(entry)
            if norm <= target:
                result.status = Status.CONVERGED_RTOL if norm <= p["rtol"] * norm0 else Status.CONVERGED_ATOL
                break
            if j == max_iterations:
                break
            inner = solver.solve(u, atol=max(forcing * norm, target))
            result.newton_iterations += inner.iterations
            result.inner_iterations += inner.inner_iterations
            entry.update(tresca_status=str(inner.status), newton_iterations=inner.iterations,
                         krylov_iterations=inner.inner_iterations)
            logger.info("  fixed point %3d  |y^| %.3e  rel %.2e  Tresca: %s after %d Newton steps",
                        j, norm, entry["relative_residual"], inner.status, inner.iterations)
            if not inner.converged:
                result.status = Status.DIVERGED_INNER
                break
            slip_bound[:] = law.bound(inner.normal_force)
            norm = solver.residual(u).norm
    result.iterations = len(result.history) - 1
    return result


def _check_arguments(problem: ContactProblem, forcing: float, max_iterations: int) -> None:
    """Raise unless the law's bound depends on the normal force and ``forcing``, ``max_iterations`` are valid."""
    slope = problem.comm.allreduce(problem.law.slope_bound, op=MPI.MAX)
    require(slope > 0.0, "friction", "the fixed-point method needs a law whose bound depends on the normal "
            "force (Coulomb with F > 0)")
    require(0.0 < forcing < 1.0, "forcing", f"must lie in (0, 1), got {forcing!r}")
    require(max_iterations >= 1, "max_iterations", f"must be >= 1, got {max_iterations!r}")
