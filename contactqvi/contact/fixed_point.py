"""Coulomb friction as the fixed point of Tresca problems: the classical method.

The literature's way to Coulomb friction (seed 000, refs. [2, 3]): given the
normal forces lambda^(j) of the previous iterate, solve the Tresca problem with
the slip bound s = F lambda^(j) (a VI of the second kind) and repeat,
    s^(j+1) = F lambda(u^(j)),   u^(j+1) = Tresca solution for s^(j+1), started from u^(j).
Each Tresca problem is solved by the same SCD semismooth* Newton method
(:class:`~contactqvi.contact.scd_newton.SCDNewtonSolver` with a
:class:`~contactqvi.contact.nodal.FrictionLaw` of given bound). The Tresca solves
are inexact: each stops when its own residual is below ``forcing`` times the
current Coulomb residual (or the final target), which keeps the outer iteration
convergent while not over-solving early Tresca problems. The method stops on
the Coulomb residual ||y^|| of (6.17), the measure the SCD Newton method uses, so
both reach the same accuracy.
"""

from __future__ import annotations

import dataclasses
import logging

from petsc4py import PETSc

from contactqvi.contact.nodal import FrictionLaw
from contactqvi.contact.problem import ContactProblem
from contactqvi.contact.scd_newton import PARAMETERS, SCDNewtonSolver
from contactqvi.parameters import require
from contactqvi.result import Result, Status

__all__ = ["TrescaFixedPointResult", "solve_tresca_fixed_point"]

logger = logging.getLogger(__name__)


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
    forcing: float = 1e-2,
    prefix: str = "tresca_",
) -> TrescaFixedPointResult:
    """Solve the Coulomb problem ``problem`` by fixed-point iteration on the slip bound, in place.

    Args:
        problem: Coulomb contact problem (``problem.law.friction`` = F > 0).
        u: initial guess (shifted displacements), overwritten by the solution.
        parameters: SCD Newton parameters of the Tresca solves; ``rtol`` and ``atol``
            are the final accuracy of the Coulomb residual.
        max_iterations: Tresca problems before giving up (status ``DIVERGED_MAX_IT``).
        forcing: each Tresca solve stops at ``forcing`` times the Coulomb residual
            at its start (and never below the final target).
        prefix: PETSc options prefix of the Newton-step KSPs of the Tresca solves.
    """
    p = PARAMETERS.check(parameters)
    require(problem.law.friction > 0.0, "friction", "the fixed-point method needs a Coulomb problem with F > 0")
    require(0.0 < forcing < 1.0, "forcing", f"must lie in (0, 1), got {forcing!r}")
    require(max_iterations >= 1, "max_iterations", f"must be >= 1, got {max_iterations!r}")
    result = TrescaFixedPointResult(status=Status.DIVERGED_MAX_IT, iterations=0)
    with result.timings.phase("solve"), SCDNewtonSolver(problem, p) as coulomb:  # residual (6.17) and gamma only
        p["gamma"] = coulomb.gamma
        point = coulomb.residual(u)
        norm0 = point.norm
        target = max(p["rtol"] * norm0, p["atol"])
        for j in range(max_iterations + 1):
            entry = {"j": j, "residual": point.norm, "relative_residual": point.norm / norm0 if norm0 else 0.0}
            result.history.append(entry)
            if point.norm <= target:
                result.status = Status.CONVERGED_ATOL if point.norm <= p["atol"] else Status.CONVERGED_RTOL
                break
            if j == max_iterations:
                break
            # s = F lambda, lambda = -theta of the current iterate's graph point (6.17).
            tresca = dataclasses.replace(problem, law=FrictionLaw(slip_bound=-problem.law.friction * point.z[:, 2]))
            with SCDNewtonSolver(tresca, {**p, "atol": max(forcing * point.norm, target)}, prefix=prefix) as solver:
                inner = solver.solve(u)
            result.newton_iterations += inner.iterations
            result.inner_iterations += inner.inner_iterations
            entry.update(tresca_status=str(inner.status), newton_iterations=inner.iterations,
                         krylov_iterations=inner.inner_iterations)
            logger.info("  fixed point %3d  |y^| %.3e  rel %.2e  Tresca: %s after %d Newton steps",
                        j, point.norm, entry["relative_residual"], inner.status, inner.iterations)
            if not inner.converged:
                result.status = Status.DIVERGED_INNER
                break
            point = coulomb.residual(u)
    result.iterations = len(result.history) - 1
    return result
