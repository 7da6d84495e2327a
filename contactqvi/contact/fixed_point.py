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
import time

from petsc4py import PETSc

from contactqvi.contact.nodal import FrictionLaw
from contactqvi.contact.problem import ContactProblem
from contactqvi.contact.scd_newton import SCDNewtonSolver, check_parameters
from contactqvi.parameters import require

__all__ = ["FixedPointResult", "solve_tresca_fixed_point"]

logger = logging.getLogger(__name__)


@dataclasses.dataclass
class FixedPointResult:
    """Outcome of :func:`solve_tresca_fixed_point`."""

    status: str  # "converged", "diverged" or the failing Tresca solve's status
    iterations: int  # Tresca problems solved
    newton_iterations: int  # SCD Newton steps over all Tresca solves
    krylov_iterations: int
    history: list[dict]
    solve_time: float  # s, wall time of the loop (after assembly)

    @property
    def converged(self) -> bool:
        return self.status == "converged"


def solve_tresca_fixed_point(
    problem: ContactProblem,
    u: PETSc.Vec,
    parameters: dict | None = None,
    max_iterations: int = 50,
    forcing: float = 1e-2,
    prefix: str = "tresca_",
) -> FixedPointResult:
    """Solve the Coulomb problem ``problem`` by fixed-point iteration on the slip bound, in place.

    Args:
        problem: Coulomb contact problem (``problem.law.friction`` = F > 0).
        u: initial guess (shifted displacements), overwritten by the solution.
        parameters: SCD Newton parameters of the Tresca solves; ``rtol`` and ``atol``
            are the final accuracy of the Coulomb residual.
        max_iterations: Tresca problems before giving up (status "diverged").
        forcing: each Tresca solve stops at ``forcing`` times the Coulomb residual
            at its start (and never below the final target).
        prefix: PETSc options prefix of the Newton-step KSPs of the Tresca solves.
    """
    p = check_parameters(parameters)
    require(problem.law.friction > 0.0, "friction", "the fixed-point method needs a Coulomb problem with F > 0")
    require(0.0 < forcing < 1.0, "forcing", f"must lie in (0, 1), got {forcing!r}")
    require(max_iterations >= 1, "max_iterations", f"must be >= 1, got {max_iterations!r}")
    t0 = time.perf_counter()
    coulomb = SCDNewtonSolver(problem, p)  # for the residual (6.17) and gamma only
    p["gamma"] = coulomb.gamma
    norm0, _, z = coulomb.approximation_step(u)
    norm = norm0
    target = max(p["rtol"] * norm0, p["atol"])
    history: list[dict] = []
    status, newton, krylov = "diverged", 0, 0
    for j in range(max_iterations + 1):
        entry = {"j": j, "residual": norm, "relative_residual": norm / norm0}
        history.append(entry)
        if norm <= target:
            status = "converged"
            break
        if j == max_iterations:
            break
        # s = F lambda, lambda = -theta of the current iterate's graph point (6.17).
        tresca = dataclasses.replace(problem, law=FrictionLaw(slip_bound=-problem.law.friction * z[:, 2]))
        solver = SCDNewtonSolver(tresca, {**p, "atol": max(forcing * norm, target)}, prefix=prefix)
        inner = solver.solve(u)
        solver.destroy()
        newton += inner.iterations
        krylov += inner.krylov_iterations
        entry.update(tresca_status=inner.status, newton_iterations=inner.iterations, krylov_iterations=inner.krylov_iterations)
        logger.info("  fixed point %3d  |y^| %.3e  rel %.2e  Tresca: %s after %d Newton steps",
                    j, norm, norm / norm0, inner.status, inner.iterations)
        if not inner.converged:
            status = f"tresca_{inner.status}"
            break
        norm, _, z = coulomb.approximation_step(u)
    coulomb.destroy()
    return FixedPointResult(status, len(history) - 1, newton, krylov, history, time.perf_counter() - t0)

