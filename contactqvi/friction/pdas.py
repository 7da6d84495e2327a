"""Primal-dual active set method (PDAS, Algorithm 1 of seed 002) and (SS) = PDAS with sigma = 1/gamma.

One iteration is one linear solve of the equality-constrained problem (4.1):
on the inactive set I the multiplier is eliminated by lambda = lambda_hat + gamma y
(a Robin term gamma m_i on the diagonal), on A+- it is the known load +-g:

    (K + gamma M_I) y = F - M (g chi_{A+} - g chi_{A-} + lambda_hat chi_I).

Sect. 4.2 shows that (PDAS) with sigma = 1/gamma is the semismooth Newton
method (SS) for (4.3); :func:`semismooth_newton_sigma` gives that sigma.
"""

from __future__ import annotations

import dataclasses
import logging
import time
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

from dolfinx import fem

from contactqvi.friction.problem import (
    ACTIVE_MINUS,
    ACTIVE_PLUS,
    INACTIVE,
    FrictionProblem,
    boundary_states,
    complementarity_residual,
)
from contactqvi.lifetime import PETScOwner
from contactqvi.linalg import OptionsDict, create_ksp, preset
from contactqvi.parameters import Parameter, Parameters, require, require_positive
from contactqvi.result import Result, Status, Timings

__all__ = [
    "PARAMETERS",
    "ActiveSetResult",
    "FrictionActiveSetSolver",
    "semismooth_newton_sigma",
]

logger = logging.getLogger(__name__)

#: ``monitor(k, y, lam, xi)``: observer of the iterates of :meth:`FrictionActiveSetSolver.solve`.
Monitor = typing.Callable[[int, fem.Function, np.ndarray, np.ndarray], None]

#: Parameters of one (PDAS)/(SS) run (:meth:`FrictionActiveSetSolver.solve`).
PARAMETERS = Parameters(
    gamma=Parameter(1e4, "regularisation parameter gamma of (P*_gamma)", minimum=0.0, exclusive=True),
    sigma=Parameter(1.0, "sigma of the set prediction (3.2c); 1/gamma gives (SS)", minimum=0.0, exclusive=True),
    max_iterations=Parameter(50, "maximal number of (PDAS) iterations (linear solves)", int, minimum=1),
    residual_reduction=Parameter(
        None, "stop when the (3.2c) residual is this factor of the initial one (inexact solve, Sect. 6.2); "
        "none: when the sets repeat", minimum=0.0, maximum=1.0, exclusive=True, optional=True,
    ),
)  # fmt: skip


def semismooth_newton_sigma(gamma: float) -> float:
    """The sigma for which (PDAS) is the semismooth Newton method (SS): sigma = 1/gamma (Sect. 4.2)."""
    require_positive("gamma", gamma)
    return 1.0 / gamma


@dataclasses.dataclass(kw_only=True)
class ActiveSetResult(Result):
    """Outcome of one (PDAS)/(SS) run.

    ``status``: CONVERGED_ACTIVE_SET (the sets repeated: (3.2) holds, Lemma 4.1),
    CONVERGED_INEXACT (the (3.2c) residual was reduced by ``residual_reduction``),
    DIVERGED_CYCLING (the sets returned to an earlier, non-consecutive configuration),
    DIVERGED_MAX_IT or DIVERGED_LINEAR_SOLVE. ``iterations``: linear solves after the
    initialisation (the paper's count); ``inner_iterations``: Krylov iterations of all
    solves, the initialisation included.

    Attributes:
        y: the primal iterate, the solver's Function ``y``: overwritten by its next
            solve (``y.copy()`` keeps it).
        lam: the multiplier lambda at the owned friction nodes (a copy).
        xi: the multiplier xi of (3.2b) at the owned friction nodes (a copy).
        states: int8 array (-1 on A-, 0 on I, +1 on A+) of the last solve.
        initial_residual: ||(3.2c)||_{L2(Gamma_f)} at the initial iterate.
    """

    y: fem.Function
    lam: np.ndarray
    xi: np.ndarray
    states: np.ndarray
    initial_residual: float

    def summary(self) -> dict[str, typing.Any]:
        return {**super().summary(), "initial_residual": self.initial_residual}


class FrictionActiveSetSolver(PETScOwner):
    """(PDAS) of seed 002 for the regularised problem (P*_gamma); (SS) with sigma = 1/gamma.

    The solver owns the system matrix K + gamma M_I, its KSP (options prefix
    ``prefix``, default :func:`contactqvi.linalg.preset` ``lu``), work vectors and
    the iterate (y, lambda, xi), all created once and reused by every
    :meth:`solve` (e.g. by the augmented Lagrangian method with changing gamma
    and lambda_hat).

    Args:
        problem: the discrete friction problem.
        prefix: PETSc options prefix of the linear solver.
        ksp_options: options of this instance's linear solver on top of the
            ``lu`` preset; set on its KSP only (other instances with the same
            prefix do not see them), overridable from the command line.
    """

    def __init__(self, problem: FrictionProblem, prefix: str = "friction_", ksp_options: OptionsDict | None = None):
        self.problem = problem
        self.A = problem.K.duplicate(copy=True)
        self.ksp = create_ksp(problem.comm, prefix, {**preset("lu"), **(ksp_options or {})}, self.A)
        self._robin = problem.K.createVecLeft()
        self._rhs = problem.K.createVecLeft()
        self.y = fem.Function(problem.V, name="y")
        self.lam = problem.boundary_zeros()
        self.xi = problem.boundary_zeros()
        #: Linear solves and Krylov iterations of this instance so far (all runs).
        self.linear_solves = 0
        self.krylov_iterations = 0

    def petsc_objects(self) -> list[typing.Any]:
        return [self.ksp, self.A, self._robin, self._rhs, self.y.x.petsc_vec]

    def solve_linear(self, gamma: float, states: np.ndarray, lam_hat: np.ndarray) -> bool:
        """Solve (4.1) for the sets ``states`` into ``y``: (K + gamma M_I) y = F - M lambda_known.

        ``lambda_known`` is +-g on A+- and lambda_hat on I (where lambda = lambda_hat + gamma y).
        Returns False if the KSP did not converge.
        """
        p = self.problem
        inactive = states == INACTIVE
        p.K.copy(self.A, structure=PETSc.Mat.Structure.SAME_NONZERO_PATTERN)
        self._robin.set(0.0)
        self._robin.array[p.boundary_dofs] = np.where(inactive, gamma * p.boundary_mass, 0.0)
        self.A.setDiagonal(self._robin, addv=PETSc.InsertMode.ADD_VALUES)
        p.F.copy(self._rhs)
        known = np.where(inactive, lam_hat, states * p.g)
        self._rhs.array[p.boundary_dofs] -= p.boundary_mass * known
        self.ksp.setOperators(self.A)
        self.ksp.solve(self._rhs, self.y.x.petsc_vec)
        self.y.x.scatter_forward()
        self.linear_solves += 1
        self.krylov_iterations += self.ksp.getIterationNumber()
        return self.ksp.getConvergedReason() > 0

    def _update_multipliers(self, gamma: float, states: np.ndarray, lam_hat: np.ndarray) -> None:
        """(PDAS) step 4: lambda = +-g on A+-, (3.2a) on I; xi from (3.2b) on A+-, 0 on I."""
        p = self.problem
        trace = p.trace(self.y.x.petsc_vec)
        self.lam[:] = np.where(states == INACTIVE, p.multiplier_from_state(self.y.x.petsc_vec), states * p.g)
        self.xi[:] = np.where(states == INACTIVE, 0.0, trace + (lam_hat - states * p.g) / gamma)

    def _initialise(self, gamma: float, lam_hat: np.ndarray, warm_start: bool) -> bool:
        """(PDAS) step 1: the solution of (3.2) with xi = 0 (all nodes inactive, Sect. 6), or the current iterate."""
        if warm_start:
            self.xi[:] = self.problem.trace(self.y.x.petsc_vec) + (lam_hat - self.lam) / gamma
            return True
        inactive_everywhere = np.zeros(len(self.problem.boundary_dofs), dtype=np.int8)
        if not self.solve_linear(gamma, inactive_everywhere, lam_hat):
            return False
        self._update_multipliers(gamma, inactive_everywhere, lam_hat)
        return True

    def _repeats(self, states: np.ndarray, earlier: np.ndarray) -> bool:
        """True on every rank if ``states`` equals ``earlier`` at every friction node (collective)."""
        return self.problem.comm.allreduce(bool(np.array_equal(states, earlier)), op=MPI.LAND)

    def _stop_reason(self, states: np.ndarray, previous: list[np.ndarray], max_iterations: int) -> Status:
        """(PDAS) step 3: stop when the predicted sets equal those of the last solve (Lemma 4.1)."""
        if previous and self._repeats(states, previous[-1]):
            return Status.CONVERGED_ACTIVE_SET
        if any(self._repeats(states, earlier) for earlier in previous[:-1]):
            return Status.DIVERGED_CYCLING
        if len(previous) >= max_iterations:
            return Status.DIVERGED_MAX_IT
        return Status.ITERATING

    def _step(self, gamma: float, sigma: float, states: np.ndarray, lam_hat: np.ndarray, previous: list[np.ndarray],
              reference: np.ndarray | None) -> dict[str, typing.Any] | None:  # fmt: skip
        """(PDAS) steps 4-5 for the sets ``states``; its history entry, or None if the linear solve failed."""
        start = time.perf_counter()
        if not self.solve_linear(gamma, states, lam_hat):
            return None
        self._update_multipliers(gamma, states, lam_hat)
        residual = self._residual(sigma)
        return self._record(len(previous) + 1, states, previous, residual, reference, time.perf_counter() - start)

    def _record(self, k: int, states: np.ndarray, previous: list[np.ndarray], residual: float,
                reference: np.ndarray | None, seconds: float) -> dict[str, typing.Any]:  # fmt: skip
        """History entry of iteration k: set sizes and changes, (3.2c) residual, d_lambda (6.1)."""
        p = self.problem
        entry = {
            "k": k,
            "A_minus": p.count(states == ACTIVE_MINUS),
            "A_plus": p.count(states == ACTIVE_PLUS),
            "inactive": p.count(states == INACTIVE),
            "changes": p.count(states != previous[-1]) if previous else None,
            "switches_between_active_sets": p.count(states * previous[-1] == -1) if previous else None,
            "residual_32c": residual,
            "d_lambda": p.boundary_norm(reference - self.lam) if reference is not None else None,
            "seconds": seconds,
        }
        logger.info(
            "  PDAS k=%3d |A-|=%5d |A+|=%5d |I|=%5d changes=%5s res(3.2c)=%.3e%s",
            k, entry["A_minus"], entry["A_plus"], entry["inactive"],
            "-" if entry["changes"] is None else entry["changes"], residual,
            "" if entry["d_lambda"] is None else f" d_lambda={entry['d_lambda']:.3e}",
        )  # fmt: skip
        return entry

    def solve(
        self,
        *,
        lam_hat: np.ndarray | None = None,
        warm_start: bool = False,
        reference: np.ndarray | None = None,
        monitor: Monitor | None = None,
        **parameters: typing.Any,
    ) -> ActiveSetResult:
        """Run (PDAS) (Algorithm 1) for (P*_gamma) with shift ``lam_hat``.

        Args:
            lam_hat: lambda_hat of (3.1) at the owned friction nodes (default 0).
            warm_start: start from the current iterate (y, lambda) of this solver,
                i.e. the result of its previous solve (xi from (3.2b)); default:
                the solution of (3.2a)-(3.2c) with xi = 0 (Sect. 6).
            reference: lambda_bar for d_lambda = ||lambda_bar - lambda^k||_{L2(Gamma_f)} (6.1).
            monitor: called as ``monitor(k, y, lam, xi)`` with the initial iterate
                (k = 0) and after every iteration (e.g. to record lambda^k for the
                rates q_lambda^k of Table 6.2); must not modify its arguments.
            parameters: values of :data:`PARAMETERS` (gamma, sigma, max_iterations,
                residual_reduction); checked before any work.
        """
        params = PARAMETERS.check(parameters)
        gamma, sigma, reduction = params["gamma"], params["sigma"], params["residual_reduction"]
        p = self.problem
        hat = p.boundary_zeros() if lam_hat is None else np.asarray(lam_hat, dtype=float)
        require(hat.shape == self.lam.shape, "lam_hat", f"must have {self.lam.shape} entries, got {hat.shape}")
        krylov, timings = self.krylov_iterations, Timings()
        with timings.phase("initialisation"):
            started = self._initialise(gamma, hat, warm_start)
        initial_residual = self._residual(sigma)
        if monitor is not None:
            monitor(0, self.y, self.lam, self.xi)
        history: list[dict[str, typing.Any]] = []
        previous: list[np.ndarray] = []
        status = Status.ITERATING if started else Status.DIVERGED_LINEAR_SOLVE
        states = boundary_states(self.xi, self.lam, p.g, sigma)
        while status == Status.ITERATING:
            status = self._stop_reason(states, previous, params["max_iterations"])
            if status != Status.ITERATING:
                break
            with timings.phase("iterations"):
                entry = self._step(gamma, sigma, states, hat, previous, reference)
            if entry is None:
                status = Status.DIVERGED_LINEAR_SOLVE
                break
            history.append(entry)
            if monitor is not None:
                monitor(len(history), self.y, self.lam, self.xi)
            previous.append(states)
            states = boundary_states(self.xi, self.lam, p.g, sigma)
            if reduction is not None and entry["residual_32c"] <= reduction * initial_residual:
                repeated = self._repeats(states, previous[-1])
                status = Status.CONVERGED_ACTIVE_SET if repeated else Status.CONVERGED_INEXACT
        return ActiveSetResult(
            status=status, iterations=len(history), inner_iterations=self.krylov_iterations - krylov,
            timings=timings, history=history, y=self.y, lam=self.lam.copy(), xi=self.xi.copy(),
            states=previous[-1] if previous else states, initial_residual=initial_residual,
        )  # fmt: skip

    def _residual(self, sigma: float) -> float:
        """||(3.2c)||_{L2(Gamma_f)} at the current iterate."""
        p = self.problem
        return p.boundary_norm(complementarity_residual(self.xi, self.lam, p.g, sigma))
