"""Uzawa's algorithm for (P*), the first-order baseline of Sect. 6 of seed 002.

lambda^(l+1) = P(lambda^l + gamma tau_f y^l) with y^l solving (2.3) for lambda^l
and P the nodal projection onto [-g, g]: the explicit counterpart of (ALM) (5.24).
It converges only for gamma in an unknown interval [alpha_1, alpha_2].
"""

from __future__ import annotations

import dataclasses
import logging
import typing

import numpy as np

from dolfinx import fem

from contactqvi.friction.problem import FrictionProblem
from contactqvi.lifetime import PETScOwner
from contactqvi.linalg import OptionsDict, create_ksp, preset
from contactqvi.parameters import Parameter, Parameters
from contactqvi.result import Result, Status, Timings

__all__ = ["PARAMETERS", "UzawaResult", "UzawaSolver"]

logger = logging.getLogger(__name__)

#: ``monitor(l, y, lam)``: observer of the iterates of :meth:`UzawaSolver.solve` (y = y^(l-1), lam = lambda^l).
Monitor = typing.Callable[[int, fem.Function, np.ndarray], None]

#: Parameters of one Uzawa run (:meth:`UzawaSolver.solve`).
PARAMETERS = Parameters(
    gamma=Parameter(10.0, "step length gamma of Uzawa's method", minimum=0.0, exclusive=True),
    atol=Parameter(
        1e-4, "stop when d_lambda < atol (with a reference; Sect. 6) or ||lambda^l - lambda^(l-1)|| < atol",
        minimum=0.0, exclusive=True,
    ),
    max_iterations=Parameter(1000, "maximal number of Uzawa iterations (linear solves)", int, minimum=1),
)  # fmt: skip


@dataclasses.dataclass(kw_only=True)
class UzawaResult(Result):
    """Outcome of the Uzawa iteration.

    ``status``: CONVERGED_ATOL (d_lambda < atol with a reference), CONVERGED_STEP
    (||lambda^(l+1) - lambda^l|| < atol without), DIVERGED_MAX_IT or
    DIVERGED_LINEAR_SOLVE. ``iterations``: linear solves (one per iteration).

    Attributes:
        y: the last primal iterate, the state (2.3) of the last-but-one multiplier
            (the solver's Function: overwritten by its next solve).
        lam: the last multiplier at the owned friction nodes.
    """

    y: fem.Function
    lam: np.ndarray


class UzawaSolver(PETScOwner):
    """Uzawa's method for (P*) on ``problem``; K is factorised once (options prefix ``prefix``).

    Args:
        problem: the discrete friction problem.
        prefix: PETSc options prefix of the linear solver.
        ksp_options: options on top of the ``lu`` preset (this instance only).
    """

    def __init__(self, problem: FrictionProblem, prefix: str = "uzawa_", ksp_options: OptionsDict | None = None):
        self.problem = problem
        self.ksp = create_ksp(problem.comm, prefix, {**preset("lu"), **(ksp_options or {})}, problem.K)
        self._rhs = problem.K.createVecLeft()
        self.y = fem.Function(problem.V, name="y")
        #: Krylov iterations of this instance so far (all runs).
        self.krylov_iterations = 0

    def petsc_objects(self) -> list[typing.Any]:
        return [self.ksp, self._rhs, self.y.x.petsc_vec]

    def _state(self, lam: np.ndarray) -> bool:
        """y solving (2.3) for the multiplier ``lam``: K y = F - M lam. False if the KSP failed."""
        p = self.problem
        p.F.copy(self._rhs)
        self._rhs.array[p.boundary_dofs] -= p.boundary_mass * lam
        self.ksp.solve(self._rhs, self.y.x.petsc_vec)
        self.y.x.scatter_forward()
        self.krylov_iterations += self.ksp.getIterationNumber()
        return self.ksp.getConvergedReason() > 0

    def solve(
        self,
        *,
        lam0: np.ndarray | None = None,
        reference: np.ndarray | None = None,
        monitor: Monitor | None = None,
        **parameters: typing.Any,
    ) -> UzawaResult:
        """Uzawa's method with step gamma from lambda^0 (default 0, Sect. 6).

        Args:
            lam0: initial multiplier at the owned friction nodes.
            reference: lambda_bar; if given the iteration stops when d_lambda^l < atol
                (the paper's criterion), otherwise when ||lambda^(l+1) - lambda^l|| < atol.
            monitor: called as ``monitor(l, y, lam)`` after every iteration with the
                state y of lambda^(l-1) and the new lambda^l; must not modify them.
            parameters: values of :data:`PARAMETERS` (gamma, atol, max_iterations).
        """
        params = PARAMETERS.check(parameters)
        p = self.problem
        lam = p.boundary_zeros() if lam0 is None else np.array(lam0, dtype=float)
        history: list[dict[str, typing.Any]] = []
        status, timings, krylov = Status.DIVERGED_MAX_IT, Timings(), self.krylov_iterations
        for iteration in range(1, params["max_iterations"] + 1):
            with timings.phase("linear solves"):
                if not self._state(lam):
                    status = Status.DIVERGED_LINEAR_SOLVE
                    break
            new = np.clip(lam + params["gamma"] * p.trace(self.y.x.petsc_vec), -p.g, p.g)
            change = p.boundary_norm(new - lam)
            lam = new
            d_lambda = p.boundary_norm(reference - new) if reference is not None else None
            history.append({"l": iteration, "d_lambda": d_lambda, "lambda_change": change})
            if monitor is not None:
                monitor(iteration, self.y, lam)
            logger.info(
                "  Uzawa l=%4d |lambda^l - lambda^(l-1)|=%.3e%s",
                iteration, change, "" if d_lambda is None else f" d_lambda={d_lambda:.3e}",
            )  # fmt: skip
            if (d_lambda if d_lambda is not None else change) < params["atol"]:
                status = Status.CONVERGED_ATOL if d_lambda is not None else Status.CONVERGED_STEP
                break
        return UzawaResult(
            status=status, iterations=len(history), inner_iterations=self.krylov_iterations - krylov, timings=timings,
            history=history, y=self.y, lam=lam,
        )  # fmt: skip
