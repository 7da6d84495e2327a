"""One status and one result for every solver of contactqvi.

:class:`Status` follows PETSc's ``KSPConvergedReason``/``SNESConvergedReason``: a
positive value converged, a negative one did not, zero is still iterating, and
every value is named. :class:`Result` holds what every iterative solver reports
(status, iteration counts, timings, history); each family derives its result from
it and adds its own fields, never re-declaring these. :class:`InnerSolveError` is how an
inner solver tells a nested method that it did not converge; errors (a PETSc error
among them) are never turned into a status: they reach the caller.
"""

from __future__ import annotations

import contextlib
import dataclasses
import enum
import time
import typing

from petsc4py import PETSc

__all__ = ["InnerSolveError", "Result", "Status", "Timings"]


class Status(enum.IntEnum):
    """Why a solver stopped. ``status > 0``: converged; ``status < 0``: not converged."""

    ITERATING = 0
    #: residual <= rtol * initial residual
    CONVERGED_RTOL = 2
    #: residual <= atol
    CONVERGED_ATOL = 3
    #: the active set (or contact state) repeated: an exact solution of the discrete problem
    CONVERGED_ACTIVE_SET = 4
    #: the change of the iterate (or of the multiplier) fell below its tolerance
    CONVERGED_STEP = 5
    #: an inexact inner solve reached the residual reduction asked of it
    CONVERGED_INEXACT = 6
    #: a fixed number of steps was asked for, with no stopping test, and done
    CONVERGED_ITERATIONS = 7
    #: the iteration limit was reached before the stopping test held
    DIVERGED_MAX_IT = -3
    #: a linear (Krylov or direct) solve failed
    DIVERGED_LINEAR_SOLVE = -4
    #: an inner solver (nested method) did not converge
    DIVERGED_INNER = -5
    #: the line search found no acceptable step
    DIVERGED_LINE_SEARCH = -6
    #: the active sets returned to an earlier configuration
    DIVERGED_CYCLING = -7
    #: the residual exceeded the divergence limit or is not finite
    DIVERGED_DTOL = -8
    #: stopped from outside (SIGTERM, SIGINT) before the stopping test held
    INTERRUPTED = -9
    #: the residual is not defined at the iterate (PETSc's SNES_DIVERGED_FUNCTION_DOMAIN):
    #: an inverted element (det F <= 0) of a hyperelastic body, or a contact geometry that a
    #: deformed facet leaves undefined (contact.mortar: a quadrilateral seen edge-on)
    DIVERGED_FUNCTION_DOMAIN = -10
    #: stopped for a new contact search: the iterate's projections left the facets of the last
    #: one (``search = "newton"``); the load path searches and solves on
    SEARCH_AGAIN = -11
    #: the residual did not fall to ``stall_factor`` (a half) of its value ``stall_iterations``
    #: Newton steps before
    DIVERGED_STALLED = -12

    @property
    def converged(self) -> bool:
        """True for every positive (converged) status."""
        return self > 0

    def __str__(self) -> str:
        return self.name.lower()


class InnerSolveError(Exception):
    """An inner solver stopped without converging; the nested method ends with ``DIVERGED_INNER``.

    Only non-convergence raises it, with the inner solver's reason in the message. It is
    not a ``RuntimeError``, so a handler of it never catches ``PETSc.Error``.
    """


class Timings(dict):
    """Wall-clock seconds per named phase, accumulated over calls of :meth:`phase`.

    Each phase is also a PETSc log stage of the same name, so ``-log_view`` splits
    PETSc's events by phase.
    """

    _stages: typing.ClassVar[dict[str, PETSc.Log.Stage]] = {}

    @contextlib.contextmanager
    def phase(self, name: str) -> typing.Iterator[None]:
        """Add the time spent in the ``with`` block to the phase ``name``."""
        stage = self._stages.get(name)
        if stage is None:
            stage = self._stages[name] = PETSc.Log.Stage(name)
        stage.push()
        start = time.perf_counter()
        try:
            yield
        finally:
            self[name] = self.get(name, 0.0) + time.perf_counter() - start
            stage.pop()


@dataclasses.dataclass(kw_only=True)
class Result:
    """What every iterative solver reports.

    Attributes:
        status: why the solver stopped (:class:`Status`).
        iterations: outer iterations (Newton steps, active-set solves, ...).
        inner_iterations: iterations of the inner solver summed over the run
            (Krylov iterations, inner Newton steps; 0 when there is none).
        timings: seconds per phase.
        history: one dict per iteration, written to ``summary.json``.
    """

    status: Status
    iterations: int
    inner_iterations: int = 0
    timings: Timings = dataclasses.field(default_factory=Timings)
    history: list[dict[str, typing.Any]] = dataclasses.field(default_factory=list)

    @property
    def converged(self) -> bool:
        return self.status.converged

    def summary(self) -> dict[str, typing.Any]:
        """The common fields as plain data for ``summary.json``."""
        return {
            "status": str(self.status),
            "converged": self.converged,
            "iterations": self.iterations,
            "inner_iterations": self.inner_iterations,
            "timings": dict(self.timings),
            "history": self.history,
        }
