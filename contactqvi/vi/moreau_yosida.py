"""Path-following smoothed Moreau-Yosida regularisation (PFMY), (59)-(60) of seed 003."""

from __future__ import annotations

import dataclasses
import logging

from petsc4py import PETSc

import ufl

from dolfinx import fem

from contactqvi.lifetime import PETScOwner
from contactqvi.linalg import create_snes, preset
from contactqvi.result import Result, Status
from contactqvi.vi.nonlinear import NonlinearFormProblem, snes_converged_reason, snes_status
from contactqvi.vi.problem import ObstacleProblem

__all__ = ["huber", "huber_derivative", "PFMYResult", "PathFollowingMoreauYosida", "DEFAULT_NEWTON_OPTIONS"]

logger = logging.getLogger(__name__)

#: SNES defaults of every PFMY subproblem (override with -<prefix>snes_... on the command line).
DEFAULT_NEWTON_OPTIONS = {
    "snes_type": "newtonls",
    "snes_linesearch_type": "bt",
    "snes_rtol": 1e-9,
    "snes_atol": 1e-13,
    "snes_stol": 1e-12,
    "snes_max_it": 100,
    **preset("lu"),
}


def huber(t: ufl.core.expr.Expr, rho: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """Huber-type smoothing sigma_rho(t) of max(0, t), (59)."""
    return ufl.conditional(ufl.le(t, 0), 0, ufl.conditional(ufl.lt(t, rho), t**2 / (2 * rho), t - rho / 2))


def huber_derivative(t: ufl.core.expr.Expr, rho: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """Derivative G_sigma_rho(t) of (59): 0, t/rho, 1 on the three pieces."""
    return ufl.conditional(ufl.le(t, 0), 0, ufl.conditional(ufl.lt(t, rho), t / rho, 1))


@dataclasses.dataclass(kw_only=True)
class PFMYResult(Result):
    """One path-following run; ``iterations`` are the Newton steps summed over the path.

    The status is the first failure of a subproblem's Newton solve, if any (the path
    is followed to its end anyway), else that of the last subproblem.

    Attributes:
        rhos: the parameters visited.
        level_iterations: Newton steps per parameter.
    """

    rhos: list[float]
    level_iterations: list[int]


class PathFollowingMoreauYosida(PETScOwner):
    """Solve (60) for rho_0 > rho_1 > ... > rho_J by Newton's method (SNES), warm-started.

    The penalty (1/rho) (sigma_rho(u - theta), v) makes the problem smooth (C^1);
    each solution is the initial guess for the next, smaller rho.

    Args:
        problem: the obstacle problem; its Function ``u`` is the iterate.
        prefix: PETSc options prefix of the SNES.
    """

    def __init__(self, problem: ObstacleProblem, prefix: str = "obstacle_pfmy_"):
        self.problem = problem
        V, u = problem.V, problem.u
        v, du = ufl.TestFunction(V), ufl.TrialFunction(V)
        self.rho = fem.Constant(V.mesh, PETSc.ScalarType(1.0))
        t = u - problem.obstacle
        dx = problem.dx
        F = ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx + (huber(t, self.rho) / self.rho - problem.source) * v * dx
        J = ufl.inner(ufl.grad(du), ufl.grad(v)) * ufl.dx + huber_derivative(t, self.rho) / self.rho * du * v * dx
        self.nonlinear = NonlinearFormProblem(fem.form(F), fem.form(J), u, problem.bcs)
        self.snes = create_snes(problem.comm, prefix, DEFAULT_NEWTON_OPTIONS)
        self.nonlinear.attach(self.snes)
        self.x = u.x.petsc_vec.duplicate()

    def petsc_objects(self) -> list[PETSc.Object | PETScOwner]:
        return [self.snes, self.x, self.nonlinear]

    def solve(self, rhos: list[float], obstacle: fem.Function | None = None) -> PFMYResult:
        """Run the path from ``problem.u`` (initial guess) through ``rhos``.

        ``obstacle``: the obstacle of this solve (None: the problem's current one).
        """
        u = self.problem.u
        if obstacle is not None:
            self.problem.set_obstacle(obstacle)
        result = PFMYResult(status=Status.ITERATING, iterations=0, rhos=list(rhos), level_iterations=[])
        for rho in rhos:
            self.rho.value = rho
            u.x.petsc_vec.copy(self.x)
            with result.timings.phase("newton"):
                self.snes.solve(None, self.x)
            self.x.copy(u.x.petsc_vec)
            u.x.scatter_forward()
            result.level_iterations.append(self.snes.getIterationNumber())
            result.inner_iterations += self.snes.getLinearSolveIterations()
            status = snes_status(self.snes)
            if not status.converged:
                # keep following the path: the next subproblem (and PDAS) start from this iterate
                logger.info("PFMY: Newton stopped at rho = %.1e (%s)", rho, snes_converged_reason(self.snes))
            if result.status.converged or result.status == Status.ITERATING:
                result.status = status
            result.history.append({"rho": rho, "newton": result.level_iterations[-1], "status": str(status)})
        result.iterations = sum(result.level_iterations)
        return result
