"""Frictionless contact (F = 0) by PETSc's SNES VI: the peer of the SCD Newton method.

With F = 0 the GE (6.3) is the Signorini problem: minimise 1/2 u^T A u - l^T u
subject to u3 >= 0 at every contact node (shifted displacements). PETSc's
reduced-space active-set Newton method (``vinewtonrsls``, through
:class:`contactqvi.vi.SNESVariationalInequality`) solves it with nodal bounds;
the Newton systems are the rows and columns of A on the inactive set.
"""

from __future__ import annotations

from petsc4py import PETSc

import numpy as np

from contactqvi.contact.problem import ContactProblem
from contactqvi.linalg import OptionsDict
from contactqvi.parameters import require
from contactqvi.vi.nonlinear import AffineProblem
from contactqvi.vi.snes_vi import SNESVariationalInequality, SNESVIResult

__all__ = ["SIGNORINI_VI_OPTIONS", "solve_signorini_vi"]

#: Defaults (any ``-{prefix}...`` option overrides): the nonlinear test on the reduced
#: residual, the inactive-set systems (submatrices of A, no near-nullspace) to 1e-10.
SIGNORINI_VI_OPTIONS: OptionsDict = {
    "snes_rtol": 1e-12,
    "snes_atol": 0.0,
    "snes_stol": 0.0,
    "snes_max_it": 100,
    "ksp_rtol": 1e-10,
}


def solve_signorini_vi(
    problem: ContactProblem,
    u: PETSc.Vec,
    options: OptionsDict | None = None,
    prefix: str = "signorini_vi_",
    ksp: str = "cg_gamg",
) -> SNESVIResult:
    """Solve the frictionless problem by SNES VI from ``u`` (in place; projected onto the bounds first).

    Args:
        problem: contact problem with ``problem.law`` frictionless (F = 0, s = 0).
        u: initial guess, overwritten by the solution (shifted displacements).
        options: PETSc options replacing :data:`SIGNORINI_VI_OPTIONS` entries.
        prefix: options prefix of the SNES (and its KSP).
        ksp: KSP preset of the inactive-set systems (:data:`contactqvi.linalg.KSP_PRESETS`).

    Returns:
        Newton steps as ``iterations``, Krylov iterations as ``inner_iterations``,
        the solve's wall time as ``timings["solve"]``.
    """
    frictionless = problem.law.friction == 0.0 and not np.any(problem.law.slip_bound)
    require(frictionless, "friction", "SNES VI solves the frictionless problem only (F = 0, no slip bound)")
    defaults = {**SIGNORINI_VI_OPTIONS, **(options or {})}
    with AffineProblem(problem.A, problem.load) as residual:
        with SNESVariationalInequality(residual, prefix, ksp, defaults) as vi:
            vi.lower.array.reshape(-1, 3)[problem.contact_blk, 2] = 0.0
            return vi.solve(u)
