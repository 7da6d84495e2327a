"""Frictionless contact (F = 0) by PETSc's SNES VI: the peer of the SCD Newton method.

With F = 0 the GE (6.3) is the Signorini problem: minimise 1/2 u^T A u - l^T u
subject to u3 >= 0 at every contact node (shifted displacements). PETSc's
reduced-space active-set Newton method (``vinewtonrsls``, through
:class:`contactqvi.vi.SNESVariationalInequality`) solves it with nodal bounds;
the Newton systems are the rows and columns of A on the inactive set.

The inactive-set systems get the rigid-body near-nullspace through
:class:`~contactqvi.vi.snes_vi.EmbeddedInactivePC` (GAMG on A with the active rows
eliminated, block size 3). Measured (benchmarks/coulomb_peers.py, lev 6 and 7, all
six cases, 1 rank): CG + GAMG on the submatrices PETSc extracts (no near-nullspace)
needs about 60 CG iterations per Newton step at rtol 1e-2 and 160 at rtol 1e-10;
with the embedded PC 4-5 and 20. The six lev-7 solves take 51 s (CPU) against 230 s
at rtol 1e-2 and 283 s at rtol 1e-10 without it. The near-nullspace restricted to
the kept rows on the submatrices (block size 1) cuts the CG iterations as much,
but each GAMG set-up costs three times as much (lev 7 d1/L1: 27 s against 8 s);
GMRES + BoomerAMG and MUMPS on the submatrices are 10 and 20 times slower (lev 6
d1/L1). Of the Krylov tolerances 1e-1 ... 1e-10, 1e-2 is the fastest (1e-3 and
1e-4 within 7 %), and the final ||y^|| still meets 1e-12 ||y^0||.
"""

from __future__ import annotations

from mpi4py import MPI
from petsc4py import PETSc

from contactqvi.contact.problem import ContactProblem
from contactqvi.linalg import OptionsDict
from contactqvi.parameters import require
from contactqvi.vi.nonlinear import AffineProblem
from contactqvi.vi.snes_vi import SNESVariationalInequality, SNESVIResult

__all__ = ["SIGNORINI_VI_OPTIONS", "solve_signorini_vi"]

#: Defaults (any ``-{prefix}...`` option overrides): the nonlinear test on the reduced
#: residual; the inactive-set systems to rtol 1e-2 (inexact Newton steps).
SIGNORINI_VI_OPTIONS: OptionsDict = {
    "snes_rtol": 1e-12,
    "snes_atol": 0.0,
    "snes_stol": 0.0,
    "snes_max_it": 100,
    "ksp_rtol": 1e-2,
}


def solve_signorini_vi(
    problem: ContactProblem,
    u: PETSc.Vec,
    options: OptionsDict | None = None,
    prefix: str = "signorini_vi_",
    ksp: str = "cg_gamg",
    near_nullspace: bool = True,
) -> SNESVIResult:
    """Solve the frictionless problem by SNES VI from ``u`` (in place; projected onto the bounds first).

    Args:
        problem: contact problem whose law has no friction (slip bound b = 0 at every node).
        u: initial guess, overwritten by the solution (shifted displacements).
        options: PETSc options replacing :data:`SIGNORINI_VI_OPTIONS` entries.
        prefix: options prefix of the SNES (and its KSP).
        ksp: KSP preset of the inactive-set systems (:data:`contactqvi.linalg.KSP_PRESETS`).
        near_nullspace: precondition them on the full space with the rigid-body modes
            (:class:`~contactqvi.vi.snes_vi.EmbeddedInactivePC`; its PC options under
            ``{prefix}embedded_``); False: the preset's PC on PETSc's submatrices.

    Returns:
        Newton steps as ``iterations``, Krylov iterations as ``inner_iterations``,
        the solve's wall time as ``timings["solve"]``.
    """
    frictional = problem.comm.allreduce(problem.law.frictional, op=MPI.LOR)
    require(not frictional, "friction", "SNES VI solves the frictionless problem only (slip bound b = 0)")
    defaults = {**SIGNORINI_VI_OPTIONS, **(options or {})}
    modes = problem.near_nullspace() if near_nullspace else None
    with AffineProblem(problem.A, problem.load) as residual:
        with SNESVariationalInequality(residual, prefix, ksp, defaults, modes) as vi:
            vi.lower.array.reshape(-1, 3)[problem.contact_blk, 2] = 0.0
            result = vi.solve(u)
    if modes is not None:
        modes.destroy()
    return result
