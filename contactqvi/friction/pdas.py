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
from contactqvi.linalg import create_ksp, ksp_converged_reason
from contactqvi.parameters import require, require_positive

__all__ = [
    "ActiveSetResult",
    "PrimalDualActiveSet",
    "DEFAULT_KSP_OPTIONS",
    "semismooth_newton_sigma",
]

logger = logging.getLogger(__name__)

#: ``monitor(k, y, lam, xi)``: observer of the iterates of :meth:`PrimalDualActiveSet.solve`.
Monitor = typing.Callable[[int, fem.Function, PETSc.Vec, PETSc.Vec], None]

#: "All linear systems are solved exactly" (Sect. 6): sparse LU by MUMPS.
DEFAULT_KSP_OPTIONS = {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"}


def semismooth_newton_sigma(gamma: float) -> float:
    """The sigma for which (PDAS) is the semismooth Newton method (SS): sigma = 1/gamma (Sect. 4.2)."""
    require_positive("gamma", gamma)
    return 1.0 / gamma


@dataclasses.dataclass
class ActiveSetResult:
    """Outcome of one (PDAS)/(SS) run.

    Attributes:
        y: the primal iterate (a dolfinx Function named ``y``).
        lam: the multiplier lambda at the owned friction nodes (PETSc Vec).
        xi: the multiplier xi of (3.2b) at the owned friction nodes (PETSc Vec).
        states: int8 array (-1 on A-, 0 on I, +1 on A+) of the last solve.
        status: ``converged`` (sets repeated, Lemma 4.1), ``inexact`` (the (3.2c)
            residual was reduced by the requested factor), ``cycling`` (the sets
            returned to an earlier, non-consecutive configuration) or
            ``max_iterations``.
        iterations: number of linear solves after the initialisation (the
            paper's iteration count).
        initial_residual: ||(3.2c)||_{L2(Gamma_f)} at the initial iterate.
        history: one dict per iteration (sizes of the sets, changes, residuals, d_lambda).
    """

    y: fem.Function
    lam: PETSc.Vec
    xi: PETSc.Vec
    states: np.ndarray
    status: str
    iterations: int
    initial_residual: float
    history: list[dict[str, typing.Any]]

    @property
    def converged(self) -> bool:
        """True if the run ended with a solution of (3.2) or the requested inexact reduction."""
        return self.status in ("converged", "inexact")


class PrimalDualActiveSet:
    """(PDAS) of seed 002 for the regularised problem (P*_gamma); (SS) with sigma = 1/gamma.

    The solver owns the system matrix K + gamma M_I, its KSP (options prefix
    ``prefix``, default direct LU) and work vectors; it can be called repeatedly
    (e.g. by the augmented Lagrangian method) with different gamma and lambda_hat.

    Args:
        problem: the discrete friction problem.
        prefix: PETSc options prefix of the linear solver.
        ksp_options: options of this instance's linear solver on top of
            :data:`DEFAULT_KSP_OPTIONS`; set on its KSP only (other instances with
            the same prefix do not see them), overridable from the command line.
    """

    def __init__(
        self,
        problem: FrictionProblem,
        prefix: str = "friction_",
        ksp_options: dict[str, typing.Any] | None = None,
    ):
        self.problem = problem
        self.A = problem.K.duplicate(copy=True)
        self.ksp = create_ksp(problem.comm, prefix, {**DEFAULT_KSP_OPTIONS, **(ksp_options or {})}, self.A)
        self._robin = problem.K.createVecLeft()
        self._rhs = problem.K.createVecLeft()
        self._work = problem.K.createVecLeft()
        self.linear_solves = 0

    def destroy(self) -> None:
        for obj in (self.ksp, self.A, self._robin, self._rhs, self._work):
            obj.destroy()

    def solve_linear(self, gamma: float, states: np.ndarray, lam_hat: np.ndarray, y: PETSc.Vec) -> None:
        """Solve (4.1) for the sets ``states``: (K + gamma M_I) y = F - M lambda_known.

        ``lambda_known`` is +-g on A+- and lambda_hat on I (where lambda = lambda_hat + gamma y).
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
        self.ksp.solve(self._rhs, y)
        self.linear_solves += 1
        if self.ksp.getConvergedReason() <= 0:
            raise RuntimeError(f"linear solve failed: {ksp_converged_reason(self.ksp)}")

    def _update_multipliers(
        self, gamma: float, states: np.ndarray, lam_hat: np.ndarray, y: PETSc.Vec, lam: PETSc.Vec, xi: PETSc.Vec
    ) -> None:
        """(PDAS) step 4: lambda = +-g on A+-, (3.2a) on I; xi from (3.2b) on A+-, 0 on I."""
        p = self.problem
        trace = p.trace(y)
        lam.array[:] = np.where(states == INACTIVE, p.multiplier_from_state(y, self._work), states * p.g)
        xi.array[:] = np.where(states == INACTIVE, 0.0, trace + (lam_hat - states * p.g) / gamma)

    def solve(
        self,
        gamma: float,
        sigma: float = 1.0,
        lam_hat: PETSc.Vec | None = None,
        initial: tuple[PETSc.Vec, PETSc.Vec] | None = None,
        reference: PETSc.Vec | None = None,
        max_iterations: int = 50,
        residual_reduction: float | None = None,
        monitor: Monitor | None = None,
    ) -> ActiveSetResult:
        """Run (PDAS) (Algorithm 1) for (P*_gamma) with shift ``lam_hat``.

        Args:
            gamma: regularisation parameter gamma > 0 of (P*_gamma).
            sigma: the parameter sigma > 0 of (3.2c); 1/gamma gives (SS).
            lam_hat: lambda_hat of (3.1) as a nodal boundary vector (default 0).
            initial: (y0, lambda0) to start from (xi0 from (3.2b)); default: the
                solution of (3.2a)-(3.2c) with xi = 0, i.e. all nodes inactive (Sect. 6).
            reference: lambda_bar for d_lambda = ||lambda_bar - lambda^k||_{L2(Gamma_f)} (6.1).
            max_iterations: bound on the number of iterations.
            residual_reduction: if given (e.g. 0.5), stop as soon as the (3.2c)
                residual is at most this factor times the initial one (the
                inexact inner solve of (ALM), Sect. 6.2).
            monitor: called as ``monitor(k, y, lam, xi)`` with the initial iterate
                (k = 0) and after every iteration (e.g. to record lambda^k for the
                rates q_lambda^k of Table 6.2); must not modify its arguments.

        Returns:
            The final iterate with status and per-iteration history.
        """
        require_positive("gamma", gamma)
        require_positive("sigma", sigma)
        require(
            isinstance(max_iterations, (int, np.integer)) and max_iterations >= 1,
            "max_iterations",
            f"must be an integer >= 1, got {max_iterations!r}",
        )
        if residual_reduction is not None:
            require(0 < residual_reduction < 1, "residual_reduction", f"must be in (0, 1), got {residual_reduction!r}")
        p = self.problem
        g = p.g
        lam = p.create_boundary_vector()
        xi = p.create_boundary_vector()
        hat = np.zeros(len(p.boundary_dofs)) if lam_hat is None else lam_hat.array_r.copy()
        y = fem.Function(p.V, name="y")
        inactive_everywhere = np.zeros(len(p.boundary_dofs), dtype=np.int8)

        if initial is None:
            self.solve_linear(gamma, inactive_everywhere, hat, y.x.petsc_vec)
            self._update_multipliers(gamma, inactive_everywhere, hat, y.x.petsc_vec, lam, xi)
        else:
            initial[0].copy(y.x.petsc_vec)
            initial[1].copy(lam)
            xi.array[:] = p.trace(y.x.petsc_vec) + (hat - lam.array_r) / gamma
        y.x.scatter_forward()

        def residual() -> float:
            return p.boundary_norm(complementarity_residual(xi.array_r, lam.array_r, g, sigma))

        initial_residual = residual()
        if monitor is not None:
            monitor(0, y, lam, xi)
        history: list[dict[str, typing.Any]] = []
        previous: list[np.ndarray] = []
        status, iterations = "max_iterations", 0
        states = boundary_states(xi.array_r, lam.array_r, g, sigma)
        while True:
            # Step 3: stop when the predicted sets equal those of the last solve (Lemma 4.1).
            if previous and p.comm.allreduce(bool(np.array_equal(states, previous[-1])), op=MPI.LAND):
                status = "converged"
                break
            if any(p.comm.allreduce(bool(np.array_equal(states, s)), op=MPI.LAND) for s in previous[:-1]):
                status = "cycling"
                break
            if iterations >= max_iterations:
                break
            start = time.perf_counter()
            self.solve_linear(gamma, states, hat, y.x.petsc_vec)
            y.x.scatter_forward()
            self._update_multipliers(gamma, states, hat, y.x.petsc_vec, lam, xi)
            iterations += 1
            entry = {
                "k": iterations,
                "A_minus": p.count(states == ACTIVE_MINUS),
                "A_plus": p.count(states == ACTIVE_PLUS),
                "inactive": p.count(states == INACTIVE),
                "changes": p.count(states != previous[-1]) if previous else None,
                "switches_between_active_sets": p.count(states * previous[-1] == -1) if previous else None,
                "residual_32c": residual(),
                "d_lambda": p.boundary_norm(reference.array_r - lam.array_r) if reference is not None else None,
                "seconds": time.perf_counter() - start,
            }
            history.append(entry)
            if monitor is not None:
                monitor(iterations, y, lam, xi)
            logger.info(
                "  PDAS k=%3d |A-|=%5d |A+|=%5d |I|=%5d changes=%5s res(3.2c)=%.3e%s",
                entry["k"], entry["A_minus"], entry["A_plus"], entry["inactive"],
                "-" if entry["changes"] is None else entry["changes"], entry["residual_32c"],
                "" if entry["d_lambda"] is None else f" d_lambda={entry['d_lambda']:.3e}",
            )  # fmt: skip
            previous.append(states)
            states = boundary_states(xi.array_r, lam.array_r, g, sigma)
            if residual_reduction is not None and entry["residual_32c"] <= residual_reduction * initial_residual:
                repeated = p.comm.allreduce(bool(np.array_equal(states, previous[-1])), op=MPI.LAND)
                status = "converged" if repeated else "inexact"
                break
        return ActiveSetResult(
            y=y,
            lam=lam,
            xi=xi,
            states=previous[-1] if previous else states,
            status=status,
            iterations=iterations,
            initial_residual=initial_residual,
            history=history,
        )
