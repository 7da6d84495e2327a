"""Augmented Lagrangian method (ALM, Algorithm 3 of seed 002) for the dual problem (P*).

Step 2 of (ALM) is the regularised problem (P*_gamma) with lambda_hat = lambda^l,
solved by (PDAS) either exactly (until the active sets repeat) or inexactly
(until the initial (3.2c) residual is reduced by a factor, Sect. 6.2). The
penalty gamma may change with l (e.g. gamma_l = 10^l, Table 6.5).
"""

from __future__ import annotations

import dataclasses
import logging
import typing

from petsc4py import PETSc

import numpy as np

from dolfinx import fem

from contactqvi.friction.pdas import PrimalDualActiveSet
from contactqvi.parameters import require, require_positive

__all__ = ["ALMResult", "augmented_lagrangian", "INNER_SOLVES"]

logger = logging.getLogger(__name__)

#: Exact: (PDAS) until the sets repeat; inexact: until the (3.2c) residual halves.
INNER_SOLVES = ("exact", "inexact")

GammaSchedule = typing.Callable[[int], float]


@dataclasses.dataclass
class ALMResult:
    """Outcome of (ALM).

    Attributes:
        y: the last primal iterate y^l.
        lam: the last multiplier lambda^l (nodal boundary PETSc Vec).
        status: ``converged`` (tolerance met), ``max_outer`` (tolerance not met),
            ``completed`` (no tolerance: the requested number of steps was run) or
            ``inner_<status>`` (an inner (PDAS) solve failed, e.g. ``inner_cycling``;
            y and lam are then the last accepted iterate, or step 1's iterate).
        outer_iterations: number of (ALM) steps l.
        linear_solves: all linear solves, including the initialisation of step 1.
        history: per step l: gamma_l, inner (PDAS) iterations and status,
            d_lambda^l (6.1) if a reference is given, ||lambda^l - lambda^(l-1)||.
    """

    y: fem.Function
    lam: PETSc.Vec
    status: str
    outer_iterations: int
    linear_solves: int
    history: list[dict[str, typing.Any]]

    @property
    def converged(self) -> bool:
        """True if the tolerance was met, or if no tolerance was given and every step succeeded."""
        return self.status in ("converged", "completed")


def augmented_lagrangian(
    pdas: PrimalDualActiveSet,
    gamma: float | GammaSchedule,
    inner: str = "exact",
    sigma: float = 1.0,
    lam0: PETSc.Vec | None = None,
    reference: PETSc.Vec | None = None,
    tol: float | None = None,
    max_outer: int = 7,
    max_inner: int = 50,
    residual_reduction: float = 0.5,
) -> ALMResult:
    """Run (ALM): lambda^(l+1) solves (3.2a)-(3.2c) with lambda_hat = lambda^l.

    Args:
        pdas: the (PDAS) solver of the problem (its KSP is reused).
        gamma: the penalty gamma > 0, or a schedule l -> gamma_l (l = 1, 2, ...).
        inner: ``exact`` or ``inexact`` solve of the auxiliary problem.
        sigma: sigma of the inner (PDAS) (1 in Sect. 6).
        lam0: lambda^0 (default 0). Step 1 starts (PDAS) from the solution with
            xi = 0 (Sect. 6); step l > 1 from the previous iterate (y^l, lambda^l).
        reference: lambda_bar for d_lambda^l (6.1).
        tol: stop when d_lambda^l < tol (with a reference) or
            ||lambda^l - lambda^(l-1)||_{L2(Gamma_f)} < tol (without); None runs
            ``max_outer`` steps.
        max_outer: maximal number of (ALM) steps.
        max_inner: maximal (PDAS) iterations per step.
        residual_reduction: the factor of the inexact inner solve.
    """
    require(inner in INNER_SOLVES, "inner", f"must be one of {INNER_SOLVES}, got {inner!r}")
    schedule: GammaSchedule
    if callable(gamma):
        schedule = gamma
    else:
        require_positive("gamma", gamma)
        schedule = lambda _l: float(gamma)  # noqa: E731
    require_positive("sigma", sigma)
    valid_outer = isinstance(max_outer, (int, np.integer)) and max_outer >= 1
    require(valid_outer, "max_outer", f"must be an integer >= 1, got {max_outer!r}")
    if tol is not None:
        require_positive("tol", tol)
    problem = pdas.problem
    lam = problem.create_boundary_vector() if lam0 is None else lam0.copy()
    solves_before = pdas.linear_solves
    history: list[dict[str, typing.Any]] = []
    state: tuple[PETSc.Vec, PETSc.Vec] | None = None
    y = None
    status = "completed" if tol is None else "max_outer"
    for step in range(1, max_outer + 1):
        gamma_l = float(schedule(step))
        require_positive("gamma", gamma_l)
        result = pdas.solve(
            gamma_l,
            sigma,
            lam_hat=lam,
            initial=state,
            reference=reference,
            max_iterations=max_inner,
            residual_reduction=residual_reduction if inner == "inexact" else None,
        )
        change = problem.boundary_norm(result.lam.array_r - lam.array_r)
        d_lambda = problem.boundary_norm(reference.array_r - result.lam.array_r) if reference is not None else None
        history.append(
            {
                "l": step,
                "gamma": gamma_l,
                "inner_iterations": result.iterations,
                "inner_status": result.status,
                "d_lambda": d_lambda,
                "lambda_change": change,
            }
        )
        logger.info(
            "ALM l=%2d gamma=%.1e inner=%2d (%s) |lambda^l - lambda^(l-1)|=%.3e%s",
            step, gamma_l, result.iterations, result.status, change,
            "" if d_lambda is None else f" d_lambda={d_lambda:.3e}",
        )  # fmt: skip
        if not result.converged:
            status = f"inner_{result.status}"
            if y is None:
                y = result.y
                result.lam.copy(lam)
            break
        result.lam.copy(lam)
        y = result.y
        state = (result.y.x.petsc_vec, result.lam)
        if tol is not None and (d_lambda if d_lambda is not None else change) < tol:
            status = "converged"
            break
    return ALMResult(
        y=y,
        lam=lam,
        status=status,
        outer_iterations=len(history),
        linear_solves=pdas.linear_solves - solves_before,
        history=history,
    )
