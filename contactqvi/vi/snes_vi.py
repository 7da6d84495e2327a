"""PETSc's reduced-space active-set Newton for variational inequalities (``vinewtonrsls``).

The alternative S-solver and the independent oracle for PFMY+PDAS: the linear
residual (grad u, grad v) - (f, v) with the bound u <= theta at every node.
"""

from __future__ import annotations

import dataclasses

from petsc4py import PETSc

import ufl

from dolfinx import fem

from contactqvi.linalg import create_snes
from contactqvi.vi.nonlinear import NonlinearFormProblem, snes_converged_reason
from contactqvi.vi.problem import ObstacleProblem

__all__ = ["SNESVIResult", "SNESVariationalInequality", "DEFAULT_VI_OPTIONS"]

DEFAULT_VI_OPTIONS = {
    "snes_type": "vinewtonrsls",
    "snes_linesearch_type": "basic",
    "snes_rtol": 1e-14,
    "snes_atol": 1e-13,
    "snes_stol": 0.0,
    "snes_max_it": 200,
    "ksp_type": "preonly",
    "pc_type": "lu",
    "pc_factor_mat_solver_type": "mumps",
}


@dataclasses.dataclass
class SNESVIResult:
    iterations: int
    reason: str
    converged: bool


class SNESVariationalInequality:
    """Obstacle problem by SNES VI; the iterate is ``problem.u``."""

    def __init__(self, problem: ObstacleProblem, prefix: str = "obstacle_vi_"):
        self.problem = problem
        V, u = problem.V, problem.u
        v, du = ufl.TestFunction(V), ufl.TrialFunction(V)
        F = ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx - problem.source * v * problem.dx
        J = ufl.inner(ufl.grad(du), ufl.grad(v)) * ufl.dx
        self.nonlinear = NonlinearFormProblem(fem.form(F), fem.form(J), u, problem.bcs)
        self.snes = create_snes(problem.comm, prefix, DEFAULT_VI_OPTIONS)
        self.nonlinear.attach(self.snes)
        self.x = u.x.petsc_vec.duplicate()
        self.lower = u.x.petsc_vec.duplicate()
        self.lower.set(PETSc.NINFINITY)
        self.upper = u.x.petsc_vec.duplicate()

    def solve(self) -> SNESVIResult:
        p = self.problem
        p.obstacle.x.petsc_vec.copy(self.upper)
        self.snes.setVariableBounds(self.lower, self.upper)
        p.u.x.petsc_vec.copy(self.x)
        self.x.pointwiseMin(self.x, self.upper)
        self.snes.solve(None, self.x)
        self.x.copy(p.u.x.petsc_vec)
        p.u.x.scatter_forward()
        p.residual(p.u, p.multiplier)
        reason = self.snes.getConvergedReason()
        return SNESVIResult(self.snes.getIterationNumber(), snes_converged_reason(self.snes), reason > 0)

    def destroy(self) -> None:
        self.snes.destroy()
        self.nonlinear.destroy()
        for obj in (self.x, self.lower, self.upper):
            obj.destroy()
