"""PETSc helpers: prefixed KSP/SNES factories, power iteration, KSP diagnostics.

Every solver object gets an options prefix; defaults given here are written to
the PETSc options database under that prefix *unless the user already set them*
(e.g. on the command line as ``-coulomb_ksp_type cg``), then ``setFromOptions()``
reads them. So anything can be overridden without touching code.
"""

from __future__ import annotations

import typing

from mpi4py import MPI
from petsc4py import PETSc

__all__ = [
    "set_default_options",
    "create_ksp",
    "create_snes",
    "power_iteration",
    "ksp_converged_reason",
]

OptionsDict = dict[str, typing.Any]


def set_default_options(prefix: str, options: OptionsDict) -> None:
    """Write ``options`` under ``prefix`` into the PETSc database, keeping user values.

    ``None`` values are flags (``-prefix_name`` without a value).
    """
    opts = PETSc.Options()
    for name, value in options.items():
        if not opts.hasName(prefix + name):
            opts[prefix + name] = "" if value is None else value


def create_ksp(
    comm: MPI.Comm, prefix: str, options: OptionsDict, A: PETSc.Mat | None = None, rtol: float | None = None
) -> PETSc.KSP:
    """KSP with options prefix ``prefix`` (ends with ``_``) and the given defaults.

    ``rtol`` is set on this KSP only (not in the shared options database, where
    it would become the default of every later solver with the same prefix); a
    ``-{prefix}ksp_rtol`` given by the user still wins.
    """
    set_default_options(prefix, options)
    ksp = PETSc.KSP().create(comm)
    ksp.setOptionsPrefix(prefix)
    if A is not None:
        ksp.setOperators(A)
    if rtol is not None:
        ksp.setTolerances(rtol=rtol)
    ksp.setFromOptions()
    return ksp


def create_snes(comm: MPI.Comm, prefix: str, options: OptionsDict) -> PETSc.SNES:
    """SNES with options prefix ``prefix`` and the given defaults (``ksp_*``/``pc_*`` included)."""
    set_default_options(prefix, options)
    snes = PETSc.SNES().create(comm)
    snes.setOptionsPrefix(prefix)
    snes.setFromOptions()
    return snes


def power_iteration(A: PETSc.Mat, x0: PETSc.Vec, iterations: int) -> float:
    """Largest-eigenvalue estimate of a symmetric positive semi-definite operator.

    ``iterations`` steps of the power method from ``x0`` (not modified); returns
    the Rayleigh quotient of the last iterate (a lower bound of lambda_max).
    """
    x = x0.copy()
    y = x0.duplicate()
    x.scale(1.0 / x.norm())
    estimate = 0.0
    for _ in range(iterations):
        A.mult(x, y)
        estimate = x.dot(y)
        x, y = y, x
        x.scale(1.0 / x.norm())
    x.destroy()
    y.destroy()
    return float(estimate)


def ksp_converged_reason(ksp: PETSc.KSP) -> str:
    """Name of the KSP's converged/diverged reason (e.g. ``CONVERGED_RTOL``)."""
    reason = ksp.getConvergedReason()
    names = {v: k for k, v in PETSc.KSP.ConvergedReason.__dict__.items() if isinstance(v, int)}
    return names.get(reason, str(reason))
