"""PETSc's reduced-space active-set Newton for variational inequalities (``vinewtonrsls``).

:class:`SNESVariationalInequality` is the one SNES-VI wrapper of contactqvi: it
takes a problem with residual/Jacobian callbacks (:mod:`contactqvi.vi.nonlinear`)
and the bounds lower <= x <= upper, and solves under an options prefix with a
named KSP preset (:data:`contactqvi.linalg.KSP_PRESETS`) for the inactive-set
systems. Its users: :class:`ObstacleSNESVI`, the alternative S-solver and the
independent oracle for PFMY+PDAS, and the Signorini peer
(:mod:`contactqvi.contact.signorini_vi`).
"""

from __future__ import annotations

import dataclasses

from petsc4py import PETSc

import ufl

from dolfinx import fem

from contactqvi.lifetime import PETScOwner
from contactqvi.linalg import OptionsDict, create_snes, preset
from contactqvi.result import Result, Status
from contactqvi.vi.nonlinear import NonlinearFormProblem, SNESProblem, snes_converged_reason, snes_status
from contactqvi.vi.problem import ObstacleProblem

__all__ = ["VI_OPTIONS", "OBSTACLE_VI_OPTIONS", "SNESVIResult", "SNESVariationalInequality", "ObstacleSNESVI"]

#: Options of every SNES VI: the method, and the line search it converged with on these machines
#: (PETSc 3.22; ``snes_linesearch_type basic``).
VI_OPTIONS: OptionsDict = {"snes_type": "vinewtonrsls", "snes_linesearch_type": "basic"}

#: Tolerances of the obstacle VI (tight: it is the oracle PFMY+PDAS is compared with).
OBSTACLE_VI_OPTIONS: OptionsDict = {"snes_rtol": 1e-14, "snes_atol": 1e-13, "snes_stol": 0.0, "snes_max_it": 200}


@dataclasses.dataclass(kw_only=True)
class SNESVIResult(Result):
    """A SNES VI solve; ``iterations`` are Newton steps, ``inner_iterations`` Krylov iterations.

    Attributes:
        reason: PETSc's name of the converged/diverged reason (e.g. ``CONVERGED_FNORM_RELATIVE``).
    """

    reason: str = ""


class SNESVariationalInequality(PETScOwner):
    """Solve F(x) = 0 subject to lower <= x <= upper (complementarity form) by ``vinewtonrsls``.

    Args:
        problem: callbacks ``F``/``J`` with their work vector ``b`` and matrix ``A``
            (:class:`~contactqvi.vi.nonlinear.NonlinearFormProblem`,
            :class:`~contactqvi.vi.nonlinear.AffineProblem`); stays the caller's.
        prefix: PETSc options prefix (``-{prefix}snes_monitor`` etc. on the command line).
        ksp: KSP preset of the inactive-set Newton systems.
        options: further defaults under ``prefix`` (tolerances; they override the preset).

    Attributes:
        lower, upper: the bounds, -inf and +inf until the caller writes them.
    """

    def __init__(self, problem: SNESProblem, prefix: str, ksp: str = "lu", options: OptionsDict | None = None):
        self.problem = problem
        comm = problem.A.getComm()
        self.snes = self._own(create_snes(comm, prefix, {**VI_OPTIONS, **preset(ksp, "ksp"), **(options or {})}))
        problem.attach(self.snes)
        self.lower = self._own(problem.b.duplicate())
        self.lower.set(PETSc.NINFINITY)
        self.upper = self._own(problem.b.duplicate())
        self.upper.set(PETSc.INFINITY)
        #: the SNES iterate: never a Vec the callbacks assemble from
        self.x = self._own(problem.b.duplicate())

    def solve(self, x: PETSc.Vec) -> SNESVIResult:
        """Solve from ``x`` (projected onto the bounds first); the solution overwrites ``x``."""
        result = SNESVIResult(status=Status.ITERATING, iterations=0)
        with result.timings.phase("solve"):
            self.snes.setVariableBounds(self.lower, self.upper)
            x.copy(self.x)
            self.x.pointwiseMax(self.x, self.lower)
            self.x.pointwiseMin(self.x, self.upper)
            self.snes.solve(None, self.x)
            self.x.copy(x)
        result.status, result.reason = snes_status(self.snes), snes_converged_reason(self.snes)
        result.iterations = self.snes.getIterationNumber()
        result.inner_iterations = self.snes.getLinearSolveIterations()
        return result


class ObstacleSNESVI(PETScOwner):
    """The obstacle problem by SNES VI: residual (grad u, grad v) - (f, v), bound u <= theta at every node.

    The iterate is ``problem.u``; after a solve ``problem.multiplier`` holds the discrete multiplier.
    """

    def __init__(self, problem: ObstacleProblem, prefix: str = "obstacle_vi_"):
        self.problem = problem
        V, u = problem.V, problem.u
        v, du = ufl.TestFunction(V), ufl.TrialFunction(V)
        F = ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx - problem.source * v * problem.dx
        J = ufl.inner(ufl.grad(du), ufl.grad(v)) * ufl.dx
        self.nonlinear = self._own(NonlinearFormProblem(fem.form(F), fem.form(J), u, problem.bcs))
        self.vi = self._own(SNESVariationalInequality(self.nonlinear, prefix, "lu", OBSTACLE_VI_OPTIONS))

    def solve(self) -> SNESVIResult:
        """Solve from ``problem.u`` for the problem's current obstacle."""
        p = self.problem
        p.obstacle.x.petsc_vec.copy(self.vi.upper)
        result = self.vi.solve(p.u.x.petsc_vec)
        p.u.x.scatter_forward()
        p.residual(p.u, p.multiplier)
        return result
