"""Augmented Lagrangian method (ALM, Algorithm 3 of seed 002) for the dual problem (P*).

Step 2 of (ALM) is the regularised problem (P*_gamma) with lambda_hat = lambda^l,
solved by (PDAS) either exactly (until the active sets repeat) or inexactly
(until the initial (3.2c) residual is reduced by a factor, Sect. 6.2). The
penalty gamma may grow with l (gamma_l = 10^l, Table 6.5).
"""

from __future__ import annotations

import dataclasses
import logging
import typing

import numpy as np

from dolfinx import fem

from contactqvi.friction import pdas as _pdas
from contactqvi.friction.pdas import ActiveSetResult, FrictionActiveSetSolver
from contactqvi.parameters import Parameter, Parameters
from contactqvi.result import Result, Status, Timings

__all__ = ["INNER_SOLVES", "PARAMETERS", "SCHEDULES", "ALMResult", "augmented_lagrangian"]

logger = logging.getLogger(__name__)

#: Exact: (PDAS) until the sets repeat; inexact: until the (3.2c) residual is reduced.
INNER_SOLVES = ("exact", "inexact")
#: gamma_l = gamma (constant) or gamma_l = 10^l (power10, the last rows of Tables 6.5/6.7).
SCHEDULES = ("constant", "power10")

#: Parameters of (ALM); sigma and the inner iteration bound are those of (PDAS).
PARAMETERS = Parameters(
    gamma=Parameter(1e2, "penalty gamma of (ALM) (schedule constant)", minimum=0.0, exclusive=True),
    schedule=Parameter("constant", "gamma_l: constant = gamma, power10 = 10^l", str, choices=SCHEDULES),
    inner=Parameter("exact", "inner (PDAS) solve: until the sets repeat, or inexact", str, choices=INNER_SOLVES),
    sigma=_pdas.PARAMETERS["sigma"],
    atol=Parameter(
        None, "stop when d_lambda < atol (with a reference) or ||lambda^l - lambda^(l-1)|| < atol; "
        "none: run max_outer steps", minimum=0.0, exclusive=True, optional=True,
    ),
    max_outer=Parameter(7, "maximal number of (ALM) steps", int, minimum=1),
    max_inner=dataclasses.replace(_pdas.PARAMETERS["max_iterations"], help="maximal (PDAS) iterations per step"),
    residual_reduction=dataclasses.replace(
        _pdas.PARAMETERS["residual_reduction"], default=0.5, optional=False,
        help="inexact inner solve: stop when the (3.2c) residual is this factor of its initial value",
    ),
)  # fmt: skip


@dataclasses.dataclass(kw_only=True)
class ALMResult(Result):
    """Outcome of (ALM).

    ``status``: CONVERGED_ATOL (d_lambda < atol with a reference), CONVERGED_STEP
    (||lambda^l - lambda^(l-1)|| < atol without), CONVERGED_ITERATIONS (no tolerance:
    the requested steps were run), DIVERGED_MAX_IT (tolerance not met) or
    DIVERGED_INNER (an inner (PDAS) solve failed; its status is in the history; y
    and lam are then the last accepted iterate, or step 1's iterate).
    ``iterations``: (ALM) steps l; ``inner_iterations``: (PDAS) iterations of all steps.

    Attributes:
        y: the last primal iterate y^l (the (PDAS) solver's Function).
        lam: the last multiplier lambda^l at the owned friction nodes.
        linear_solves: all linear solves, the initialisation of step 1 included.
    """

    y: fem.Function
    lam: np.ndarray
    linear_solves: int

    def summary(self) -> dict[str, typing.Any]:
        return {**super().summary(), "linear_solves": self.linear_solves}


def gamma_of_step(params: dict[str, typing.Any], step: int) -> float:
    """gamma_l of (ALM) step l >= 1 for the checked ``params``."""
    return 10.0**step if params["schedule"] == "power10" else params["gamma"]


def _inner_solve(
    pdas: FrictionActiveSetSolver, params: dict[str, typing.Any], step: int, lam: np.ndarray,
    reference: np.ndarray | None,
) -> ActiveSetResult:  # fmt: skip
    """Step 2 of (ALM): (P*_gamma_l) with lambda_hat = lambda^l, from the previous iterate for l > 1."""
    return pdas.solve(
        gamma=gamma_of_step(params, step), sigma=params["sigma"], max_iterations=params["max_inner"],
        residual_reduction=params["residual_reduction"] if params["inner"] == "inexact" else None,
        lam_hat=lam, warm_start=step > 1, reference=reference,
    )  # fmt: skip


def augmented_lagrangian(
    pdas: FrictionActiveSetSolver,
    *,
    lam0: np.ndarray | None = None,
    reference: np.ndarray | None = None,
    **parameters: typing.Any,
) -> ALMResult:
    """Run (ALM): lambda^(l+1) solves (3.2a)-(3.2c) with lambda_hat = lambda^l.

    Args:
        pdas: the (PDAS) solver of the problem (its KSP and iterate are reused).
        lam0: lambda^0 at the owned friction nodes (default 0). Step 1 starts (PDAS)
            from the solution with xi = 0 (Sect. 6); step l > 1 from (y^l, lambda^l).
        reference: lambda_bar for d_lambda^l (6.1) and the stopping test.
        parameters: values of :data:`PARAMETERS`, checked before any work.
    """
    params = PARAMETERS.check(parameters)
    problem = pdas.problem
    lam = problem.boundary_zeros() if lam0 is None else np.array(lam0, dtype=float)
    solves_before, timings = pdas.linear_solves, Timings()
    history: list[dict[str, typing.Any]] = []
    accepted_y: np.ndarray | None = None
    status = Status.CONVERGED_ITERATIONS if params["atol"] is None else Status.DIVERGED_MAX_IT
    for step in range(1, params["max_outer"] + 1):
        with timings.phase("inner solves"):
            result = _inner_solve(pdas, params, step, lam, reference)
        change = problem.boundary_norm(result.lam - lam)
        d_lambda = problem.boundary_norm(reference - result.lam) if reference is not None else None
        history.append({"l": step, "gamma": gamma_of_step(params, step), "inner_iterations": result.iterations,
                        "inner_status": str(result.status), "d_lambda": d_lambda, "lambda_change": change})  # fmt: skip
        logger.info(
            "ALM l=%2d gamma=%.1e inner=%2d (%s) |lambda^l - lambda^(l-1)|=%.3e%s",
            step, history[-1]["gamma"], result.iterations, result.status, change,
            "" if d_lambda is None else f" d_lambda={d_lambda:.3e}",
        )  # fmt: skip
        if not result.converged:
            status = Status.DIVERGED_INNER
            if accepted_y is None:
                lam[:] = result.lam
            else:  # back to the last accepted iterate
                pdas.y.x.array[:] = accepted_y
            break
        lam[:] = result.lam
        accepted_y = pdas.y.x.array.copy()
        if params["atol"] is not None and (d_lambda if d_lambda is not None else change) < params["atol"]:
            status = Status.CONVERGED_ATOL if d_lambda is not None else Status.CONVERGED_STEP
            break
    return ALMResult(
        status=status, iterations=len(history), inner_iterations=sum(h["inner_iterations"] for h in history),
        timings=timings, history=history, y=pdas.y, lam=lam, linear_solves=pdas.linear_solves - solves_before,
    )  # fmt: skip
