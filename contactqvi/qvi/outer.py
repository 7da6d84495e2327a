"""Outer solvers for u = H(u), H = S o Phi (o P_B): Algorithms 1 and 2 of seed 003 and C1, C3.

All methods measure the residual R(x) = x - H(x) in the H^1 norm. The Newton
step solves G_R(x) d = -R(x), G_R = Id - G_H(P_B x) G_PB(x) (Lemma 2.7 i)),
through the map's linearised system (61). Outside the ball B_R(c) of Sect. 2.3
the derivative (16) of Lemma 2.9 is G_PB(x) = s (Id - e (e, .)_X) with
s = R/||x - c||, e = (x - c)/||x - c||: a scaled identity plus a rank-one term,
handled by Sherman-Morrison with two solves of the same factorised system.

``projection_derivative = "scaled"`` drops the rank-one term, G_PB(x) = s Id.
That is not a Newton derivative of P_B (it is wrong in the radial direction),
but it reproduces the Algorithm 1/C3 counts and EOCs of Table 1, which the
exact derivative does not for R >= 4.944; docs/qvi.md gives the evidence that
the paper's computations used it. Inside B both choices are Id, so local
convergence to a solution in the interior of B is unaffected.

* ``alg1``: Algorithm 1, vanilla semismooth Newton, x_{i+1} = x_i + d.
* ``alg2``: Algorithm 2, take whichever of x_N = x_i + d and x_B = H(x_i) has
  the smaller residual (ties go to Newton).
* ``c1``: fixed-point iteration x_{i+1} = H(x_i).
* ``c3``: Algorithm 1 with a backtracking Armijo line search on the merit
  function ||R||^2/2 (sufficient decrease c = 1e-4; safeguarded quadratic
  interpolation of the step in [0.1, 0.5] times the previous one).
(C2 is ``alg1`` applied to :class:`~contactqvi.qvi.maps.RegularisedQVIMap`.)
"""

from __future__ import annotations

import dataclasses
import logging
import math
import typing

from mpi4py import MPI

import numpy as np
import ufl

import dolfinx.fem.petsc
from dolfinx import fem

from contactqvi.lifetime import PETScOwner
from contactqvi.parameters import Parameter, Parameters, require
from contactqvi.qvi.maps import CompositeMap, Evaluation
from contactqvi.qvi.projection import BallProjection
from contactqvi.result import InnerSolveError, Result, Status, Timings

__all__ = ["FIXED_POINT_PARAMETERS", "QVIResult", "FixedPointSolver"]

logger = logging.getLogger(__name__)

FIXED_POINT_PARAMETERS = Parameters(
    method=Parameter(
        "alg2", "outer method (C2 = alg1 on the regularised map)", type=str, choices=("alg1", "alg2", "c1", "c3")
    ),
    label=Parameter(None, "name in progress lines and results (default: the method)", type=str, optional=True),
    atol=Parameter(None, "stop when ||R(u)||_H1 <= atol (none: the problem data's tolerance)", minimum=0.0,
                   optional=True),
    max_iterations=Parameter(50, "maximum number of outer iterations", type=int, minimum=0),
    radius=Parameter(
        None, "radius R of the projection ball B_R(0) of Sect. 2.3 (none: no projection)",
        minimum=0.0, exclusive=True, optional=True,
    ),
    projection_derivative=Parameter(
        "exact",
        "G_PB outside the ball: exact ((16) of Lemma 2.9) or scaled (R/||x - c|| Id, the rank-one term dropped)",
        type=str,
        choices=("exact", "scaled"),
    ),
    armijo_c=Parameter(1e-4, "C3: sufficient-decrease constant", minimum=0.0, maximum=1.0, exclusive=True),
    max_backtracks=Parameter(30, "C3: maximum number of step reductions", type=int, minimum=0),
    divergence_limit=Parameter(1e10, "stop (diverged) when the residual exceeds this", minimum=0.0, exclusive=True),
)  # fmt: skip


@dataclasses.dataclass(kw_only=True)
class QVIResult(Result):
    """An outer solve. ``history[i]`` holds, for the iterate u_i, ``residual`` ||R(u_i)||_H1,
    ``taken`` (the candidate: ``newton``, ``fixed-point``, ``linesearch(alpha)``,
    ``linesearch-failed(alpha)``: no sufficient decrease within ``max_backtracks``; empty for
    i = 0), ``counts`` (inner counts of the evaluations of that step; i = 0 is the initial
    evaluation) and, with an exact solution, ``error`` ||u_i - u_exact||_{H^1_0}.

    ``status``: ``CONVERGED_ATOL`` (||R|| <= atol), ``DIVERGED_MAX_IT``, ``DIVERGED_DTOL``
    (residual above ``divergence_limit`` or not finite) or ``DIVERGED_INNER`` (Phi, S or the Newton
    system did not converge: :class:`~contactqvi.result.InnerSolveError`; errors, PETSc's among them, propagate).
    ``inner_iterations``: all inner steps (Phi Newton, PFMY Newton, PDAS, SNES VI).

    Attributes:
        method: outer method name (the label).
        solution: the last iterate u_i.
        evaluation: the evaluation of H at the last iterate (H(u), T, mould, active set).
    """

    method: str
    solution: fem.Function
    evaluation: Evaluation

    @property
    def residuals(self) -> list[float]:
        return [h["residual"] for h in self.history]

    @property
    def taken(self) -> list[str]:
        return [h["taken"] for h in self.history]

    @property
    def counts(self) -> list[dict[str, int]]:
        return [h["counts"] for h in self.history]

    @property
    def errors(self) -> list[float]:
        return [h["error"] for h in self.history if "error" in h]

    @property
    def totals(self) -> dict[str, int]:
        keys = self.counts[0].keys()
        return {k: sum(c.get(k, 0) for c in self.counts) for k in keys}

    @property
    def eocs(self) -> list[float]:
        """EOC_i of (71) from the error history (i >= 2)."""
        return _eocs(self.errors)

    @property
    def residual_eocs(self) -> list[float]:
        """(71) with ||R(u_i)|| in place of the error (equivalent near a regular solution)."""
        return _eocs(self.residuals)


def _eocs(e: list[float]) -> list[float]:
    out = []
    for i in range(2, len(e)):
        if min(e[i], e[i - 1], e[i - 2]) > 0 and e[i - 1] != e[i - 2]:
            out.append(math.log(e[i] / e[i - 1]) / math.log(e[i - 1] / e[i - 2]))
    return out


class FixedPointSolver(PETScOwner):
    """Solve u = H(u) for a composite map (see :mod:`contactqvi.qvi.maps`).

    Args:
        fmap: the map (``evaluate``, ``linearize``, ``solve_linearized``); stays the caller's.
        parameters: overrides of :data:`FIXED_POINT_PARAMETERS`.
        exact: optional exact solution (UFL expression) for error/EOC histories.
        center: owned values of the ball centre c (default 0).
    """

    def __init__(
        self,
        fmap: CompositeMap,
        parameters: dict | None = None,
        exact: ufl.core.expr.Expr | None = None,
        center: np.ndarray | None = None,
    ):
        self.params = FIXED_POINT_PARAMETERS.check(parameters)
        require(self.params["atol"] is not None, "atol", "must be a number here (build() takes the problem data's)")
        self.map = fmap
        V = fmap.V
        self.comm: MPI.Comm = V.mesh.comm
        self.n = fmap.n_owned
        u, v = ufl.TrialFunction(V), ufl.TestFunction(V)
        self.h1 = dolfinx.fem.petsc.assemble_matrix(fem.form((ufl.inner(ufl.grad(u), ufl.grad(v)) + u * v) * ufl.dx))
        self.h1.assemble()
        self.work, self.image = self.h1.createVecs()
        self.iterate = fem.Function(V, name="membrane")
        self.point = fem.Function(V, name="projected")
        self.error_form = None
        if exact is not None:
            e = self.iterate - exact
            dx = ufl.dx(metadata={"quadrature_degree": 6})
            self.error_form = fem.form(ufl.inner(ufl.grad(e), ufl.grad(e)) * dx)
        radius = self.params["radius"]
        self.projection = None if radius is None else BallProjection(fmap.stiffness, radius, center)

    def petsc_objects(self) -> list[typing.Any]:
        return [self.projection, self.work, self.image, self.h1]

    # -- helpers on owned coefficient arrays ------------------------------------------------
    def norm(self, a: np.ndarray) -> float:
        """H^1 norm of the function with owned coefficients ``a``."""
        self.work.array[:] = a
        self.h1.mult(self.work, self.image)
        return math.sqrt(max(self.work.dot(self.image), 0.0))

    def _error(self, x: np.ndarray) -> float:
        self._set(self.iterate, x)
        local = fem.assemble_scalar(self.error_form)
        return math.sqrt(max(self.comm.allreduce(local, op=MPI.SUM), 0.0))

    @staticmethod
    def _set(f: fem.Function, owned: np.ndarray) -> None:
        f.x.array[: owned.size] = owned
        f.x.scatter_forward()

    def evaluate(self, x: np.ndarray) -> tuple[Evaluation, float]:
        """H(x) = S(Phi(P_B x)) and ||R(x)||_H1."""
        y = x if self.projection is None else self.projection.apply(x)[0]
        self._set(self.point, y)
        ev = self.map.evaluate(self.point)
        return ev, self.norm(x - ev.value.x.array[: self.n])

    def newton_direction(self, x: np.ndarray, ev: Evaluation) -> np.ndarray:
        """d solving G_R(x) d = -R(x), G_R = Id - G_H(P_B x) G_PB(x) (Lemmas 2.7, 2.9).

        With ``projection_derivative = "scaled"``, G_PB(x) = s Id outside B (see the module docstring).
        """
        b = ev.value.x.array[: self.n] - x
        if self.projection is None:
            self.map.linearize(ev, 1.0)
            return self.map.solve_linearized(b)
        _, s, e = self.projection.apply(x)
        self.map.linearize(ev, s)
        z0 = self.map.solve_linearized(b)
        if e is None or self.params["projection_derivative"] == "scaled":
            return z0
        # G_R = J_s + u (e, .)_X with J_s = Id - s G_H, u = e - J_s e (Sherman-Morrison).
        w = self.map.solve_linearized(e) - e
        return z0 - w * self.projection.dot(e, z0) / (1.0 + self.projection.dot(e, w))

    def _stop(self, res: float, it: int) -> Status:
        """The status after ``it`` - 1 steps with residual ``res`` (ITERATING: take step ``it``)."""
        prm = self.params
        if res <= prm["atol"]:
            return Status.CONVERGED_ATOL
        if not math.isfinite(res) or res > prm["divergence_limit"]:
            return Status.DIVERGED_DTOL
        return Status.DIVERGED_MAX_IT if it > prm["max_iterations"] else Status.ITERATING

    def _record(self, result: QVIResult, x: np.ndarray, res: float, taken: str, counts: dict[str, int]) -> None:
        entry = {"residual": res, "taken": taken, "counts": counts}
        if self.error_form is not None:
            entry["error"] = self._error(x)
        result.history.append(entry)
        result.inner_iterations += sum(counts.values())
        it = len(result.history) - 1
        logger.info("%s it %2d  ||R||_H1 = %.3e  taken %-16s %s", result.method, it, res, taken, _format_counts(counts))

    def solve(self, u0: fem.Function) -> QVIResult:
        """Run the outer method from ``u0``."""
        method = self.params["method"]
        x = u0.x.array[: self.n].copy()
        timings = Timings()
        with timings.phase("evaluate"):
            ev, res = self.evaluate(x)
        result = QVIResult(status=Status.ITERATING, iterations=0, method=self.params["label"] or method,
                           solution=fem.Function(self.map.V, name="membrane"), evaluation=ev, timings=timings)
        self._record(result, x, res, "", dict(ev.counts))
        for it in range(1, self.params["max_iterations"] + 2):
            result.status = self._stop(res, it)
            if result.status != Status.ITERATING:
                break
            step_counts: dict[str, int] = {k: 0 for k in ev.counts}
            try:
                with result.timings.phase("step"):
                    x, ev, res, choice = self._step(method, x, ev, res, step_counts)
            except InnerSolveError as exc:  # an inner solver did not converge: report, keep the last iterate
                logger.warning("%s it %2d: %s", result.method, it, exc)
                result.status = Status.DIVERGED_INNER
                break
            self._record(result, x, res, choice, step_counts)
        result.iterations, result.evaluation = len(result.history) - 1, ev
        self._set(self.iterate, x)
        result.solution.x.array[:] = self.iterate.x.array
        return result

    def _step(self, method: str, x: np.ndarray, ev: Evaluation, res: float, step_counts: dict[str, int]):
        """One outer iteration; returns (x_{i+1}, H(x_{i+1}), ||R(x_{i+1})||, candidate taken)."""
        if method == "c1":
            x_b = ev.value.x.array[: self.n].copy()
            ev_b, res_b = self.evaluate(x_b)
            _add(step_counts, ev_b.counts)
            return x_b, ev_b, res_b, "fixed-point"
        d = self.newton_direction(x, ev)
        if method == "c3":
            return self._linesearch(x, d, res, step_counts)
        x_n = x + d
        ev_n, res_n = self.evaluate(x_n)
        _add(step_counts, ev_n.counts)
        if method == "alg1":
            return x_n, ev_n, res_n, "newton"
        # Algorithm 2, steps 7-13: the fixed-point candidate x_B = H(x_i); ties go to Newton.
        x_b = ev.value.x.array[: self.n].copy()
        ev_b, res_b = self.evaluate(x_b)
        _add(step_counts, ev_b.counts)
        if res_n <= res_b:
            return x_n, ev_n, res_n, "newton"
        return x_b, ev_b, res_b, "fixed-point"

    def _linesearch(self, x: np.ndarray, d: np.ndarray, res: float, step_counts: dict[str, int]):
        """Backtracking Armijo on f = ||R||^2/2 along the Newton direction (f'(0) = -||R||^2)."""
        f0, slope = 0.5 * res**2, -(res**2)
        alpha = 1.0
        for _ in range(self.params["max_backtracks"] + 1):
            x_t = x + alpha * d
            ev_t, res_t = self.evaluate(x_t)
            _add(step_counts, ev_t.counts)
            f_t = 0.5 * res_t**2
            if f_t <= f0 + self.params["armijo_c"] * alpha * slope:
                return x_t, ev_t, res_t, f"linesearch({alpha:.3g})"
            denominator = 2.0 * (f_t - f0 - slope * alpha)
            trial = -slope * alpha**2 / denominator if denominator > 0 else 0.5 * alpha
            last, alpha = alpha, min(max(trial, 0.1 * alpha), 0.5 * alpha)
        # No sufficient decrease after max_backtracks reductions: the smallest step is taken, and says so.
        return x_t, ev_t, res_t, f"linesearch-failed({last:.3g})"


def _add(total: dict[str, int], counts: dict[str, int]) -> None:
    for k, v in counts.items():
        total[k] = total.get(k, 0) + v


def _format_counts(counts: dict[str, int]) -> str:
    return " ".join(f"{k}={v}" for k, v in counts.items() if v)
