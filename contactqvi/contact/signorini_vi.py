"""Frictionless contact (F = 0) by PETSc's SNES VI: the peer of the SCD Newton method.

With F = 0 the GE (6.3) is the Signorini problem: minimise 1/2 u^T A u - l^T u
subject to u3 >= 0 at every contact node (shifted displacements). PETSc's
reduced-space active-set Newton method (``vinewtonrsls``) solves it with nodal
bounds; the Newton systems are the rows and columns of A on the inactive set.
"""

from __future__ import annotations

import dataclasses
import time

from petsc4py import PETSc

import numpy as np

from contactqvi.contact.problem import ContactProblem
from contactqvi.linalg import OptionsDict, create_snes
from contactqvi.parameters import require
from contactqvi.vi.nonlinear import snes_converged_reason

__all__ = ["SIGNORINI_VI_OPTIONS", "SignoriniVIResult", "solve_signorini_vi"]

#: Defaults (any ``-{prefix}...`` option overrides): the inactive-set systems by
#: CG + GAMG (submatrices of A, no near-nullspace), the nonlinear test on the
#: reduced residual.
SIGNORINI_VI_OPTIONS: OptionsDict = {
    "snes_type": "vinewtonrsls",
    "snes_linesearch_type": "basic",
    "snes_rtol": 1e-12,
    "snes_atol": 0.0,
    "snes_stol": 0.0,
    "snes_max_it": 100,
    "ksp_type": "cg",
    "ksp_rtol": 1e-10,
    "pc_type": "gamg",
}


@dataclasses.dataclass
class SignoriniVIResult:
    converged: bool
    reason: str
    iterations: int
    krylov_iterations: int
    solve_time: float  # s


def solve_signorini_vi(
    problem: ContactProblem, u: PETSc.Vec, options: OptionsDict | None = None, prefix: str = "signorini_vi_"
) -> SignoriniVIResult:
    """Solve the frictionless problem by SNES VI from ``u`` (in place; projected onto the bounds first).

    Args:
        problem: contact problem with ``problem.law`` frictionless (F = 0, s = 0).
        u: initial guess, overwritten by the solution (shifted displacements).
        options: PETSc options replacing :data:`SIGNORINI_VI_OPTIONS` entries.
    """
    frictionless = problem.law.friction == 0.0 and not np.any(problem.law.slip_bound)
    require(frictionless, "friction", "SNES VI solves the frictionless problem only (F = 0, no slip bound)")
    A, load = problem.A, problem.load
    snes = create_snes(problem.comm, prefix, {**SIGNORINI_VI_OPTIONS, **(options or {})})
    residual = A.createVecRight()
    snes.setFunction(lambda snes, x, f: (A.mult(x, f), f.axpy(-1.0, load)), residual)
    snes.setJacobian(lambda snes, x, J, P: None, A)
    lower, upper = A.createVecRight(), A.createVecRight()
    lower.set(PETSc.NINFINITY)
    upper.set(PETSc.INFINITY)
    lower.array.reshape(-1, 3)[problem.contact_blk, 2] = 0.0
    snes.setVariableBounds(lower, upper)
    u.pointwiseMax(u, lower)
    t0 = time.perf_counter()
    snes.solve(None, u)
    solve_time = time.perf_counter() - t0
    result = SignoriniVIResult(snes.getConvergedReason() > 0, snes_converged_reason(snes), snes.getIterationNumber(),
                               snes.getLinearSolveIterations(), solve_time)
    for obj in (residual, lower, upper, snes):
        obj.destroy()
    return result
