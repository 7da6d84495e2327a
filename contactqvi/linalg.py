"""PETSc helpers: prefixed KSP/SNES factories, in-place re-assembly, power iteration, KSP diagnostics.

Every solver object gets an options prefix and per-object default options: they
are put into the PETSc options database under that prefix *unless the user
already set them* (e.g. on the command line as ``-coulomb_ksp_type cg``), read by
``setFromOptions()`` and removed again. So anything can be overridden without
touching code, and two solvers with the same prefix but different defaults do not
see each other's values.
"""

from __future__ import annotations

import contextlib
import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx.fem.petsc
from dolfinx import fem

from contactqvi.parameters import require_choice

__all__ = [
    "KSP_PRESETS",
    "OptionsDict",
    "preset",
    "default_options",
    "create_ksp",
    "create_snes",
    "assemble_system",
    "reassemble_matrix",
    "power_iteration",
    "ksp_converged_reason",
    "nonzero_row_indices",
    "nonzero_rows",
    "significant",
]

OptionsDict = dict[str, typing.Any]

_GMRES_RIGHT = {"ksp_type": "fgmres", "ksp_pc_side": "right", "ksp_norm_type": "unpreconditioned", "ksp_gmres_restart": 200}

#: Named linear-solver presets, each a set of PETSc options applied under the
#: caller's prefix (anything given on the command line under that prefix wins).
#: Measured choices are in docs/coulomb.md and benchmarks/results/.
#:
#: * ``lu``: exact solves by MUMPS (``preonly``).
#: * ``cg_gamg``: CG + smoothed-aggregation AMG (SPD elasticity/Poisson systems;
#:   give the matrix the rigid-body near-nullspace, :func:`contactqvi.elasticity.rigid_motions_nullspace`).
#: * ``gmres_gamg``: GMRES stopped at the *unpreconditioned* relative residual
#:   ||b - J x|| <= rtol ||b||, right-preconditioned by one V-cycle of GAMG, in its
#:   flexible form (FGMRES: the preconditioned directions are kept, so the update of
#:   x needs no extra preconditioner application at the end of a solve; the iterates
#:   of a fixed preconditioner are GMRES's; a solve of 2-3 iterations saves a quarter
#:   of its multigrid cycles; docs/coulomb.md). The
#:   Newton-step solver of the Coulomb problem: AMG reduces all error components
#:   alike, so a residual reduced by tol is a direction accurate to about tol. With
#:   one hierarchy kept by Galerkin updates the V-cycle beats the W-cycle (lev 8, six
#:   cases, 2 ranks: same Newton steps, fewer Krylov iterations and less time;
#:   measured in docs/coulomb.md).
#: * ``gmres_ilu``: GMRES + block-Jacobi/ILU(0) as in seed 000, Sect. 7, stopped at
#:   the left-preconditioned residual (MATLAB's gmres test with a preconditioner).
#:   A 10 % reduction of that residual is met by directions that miss the smooth
#:   part of the solution, which costs Newton steps from lev 6 on.
#: * ``gmres_hypre``: as ``gmres_gamg`` with BoomerAMG (scalar coarsening; its
#:   nodal/vector interpolation variants broke down on eliminated rows here).
#: * ``gmres_pressure_schur``: as ``gmres_gamg`` with the block preconditioner of bodies with an
#:   averaged volume change (:mod:`contactqvi.contact.pressure_schur`, a ``python`` PC whose context
#:   the Newton-step solver sets: two BoomerAMG V-cycles on the Newton matrix without the bulk
#:   term), on the uncondensed displacement-pressure system, its pressure rows in force units.
#: * ``cg_jacobi``: CG + point Jacobi (cheap, for well-conditioned mass-like systems).
#: * ``gmres_jacobi``: GMRES + point Jacobi, stopped at the left-preconditioned residual: the
#:   Newton steps of a mass-like problem (the projection of a dynamic step's predictor,
#:   docs/dynamics.md Sect. 3.2), whose matrix is spectrally equivalent to its diagonal but
#:   whose rows span the masses of a graded mesh (9 orders of magnitude on the Hertz block):
#:   an unpreconditioned residual is then the heavy rows' round-off. Relative to the initial
#:   residual (the rows left after the elimination), not to a force-norm right-hand side.
KSP_PRESETS: dict[str, OptionsDict] = {
    "lu": {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps"},
    "cg_gamg": {"ksp_type": "cg", "ksp_norm_type": "unpreconditioned", "pc_type": "gamg"},
    "gmres_gamg": {
        **_GMRES_RIGHT,
        "ksp_max_it": 2000,
        "pc_type": "gamg",
        "pc_gamg_type": "agg",
    },
    "gmres_ilu": {
        "ksp_type": "gmres",
        "ksp_pc_side": "left",
        "ksp_norm_type": "preconditioned",
        "ksp_gmres_restart": 200,
        "ksp_max_it": 5000,
        "pc_type": "bjacobi",
        "sub_pc_type": "ilu",
    },
    "gmres_hypre": {
        **_GMRES_RIGHT,
        "ksp_max_it": 2000,
        "pc_type": "hypre",
        "pc_hypre_type": "boomeramg",
        "pc_hypre_boomeramg_strong_threshold": 0.5,
    },
    "gmres_pressure_schur": {**_GMRES_RIGHT, "ksp_max_it": 400, "pc_type": "python"},
    "cg_jacobi": {"ksp_type": "cg", "pc_type": "jacobi"},
    "gmres_jacobi": {"ksp_type": "gmres", "ksp_pc_side": "left", "ksp_norm_type": "preconditioned",
                     "ksp_converged_use_initial_residual_norm": True, "ksp_gmres_restart": 200, "ksp_max_it": 2000,
                     "pc_type": "jacobi"},
}


def preset(name: str, parameter: str = "pc", **overrides: typing.Any) -> OptionsDict:
    """A copy of the options of preset ``name`` (:data:`KSP_PRESETS`), with ``overrides``;
    an unknown name raises :class:`~contactqvi.parameters.ParameterError` for ``parameter``."""
    require_choice(parameter, name, KSP_PRESETS)
    return {**KSP_PRESETS[name], **overrides}


@contextlib.contextmanager
def default_options(prefix: str, options: OptionsDict) -> typing.Iterator[None]:
    """Temporarily write ``options`` under ``prefix`` into the PETSc database.

    Values the user already set are kept; the ones written here are removed on
    exit. ``True``/``None`` values are flags (``-prefix_name`` without a value).
    """
    opts = PETSc.Options()
    added = [name for name in options if not opts.hasName(prefix + name)]
    for name in added:
        value = options[name]
        opts[prefix + name] = "" if value is None or value is True else value
    try:
        yield
    finally:
        for name in added:
            opts.delValue(prefix + name)


def create_ksp(
    comm: MPI.Comm, prefix: str, options: OptionsDict, A: PETSc.Mat | None = None, rtol: float | None = None
) -> PETSc.KSP:
    """KSP with options prefix ``prefix`` (ends with ``_``) and the given defaults.

    ``rtol`` is set on this KSP only; a ``-{prefix}ksp_rtol`` given by the user still wins.
    The defaults are in the options database only during ``setFromOptions``. Options a
    preconditioner reads when it is set up (PCGAMG's multigrid options, e.g.
    ``pc_mg_cycle_type``, are read when it builds its levels inside the solve; PCBJACOBI's
    ``sub_*`` options when it makes its blocks) need
    ``with default_options(prefix, options)`` around the solve as well.
    """
    ksp = PETSc.KSP().create(comm)
    ksp.setOptionsPrefix(prefix)
    if A is not None:
        ksp.setOperators(A)
    if rtol is not None:
        ksp.setTolerances(rtol=rtol)
    with default_options(prefix, options):
        ksp.setFromOptions()
    return ksp


def create_snes(comm: MPI.Comm, prefix: str, options: OptionsDict) -> PETSc.SNES:
    """SNES with options prefix ``prefix`` and the given defaults (``ksp_*``/``pc_*`` included)."""
    snes = PETSc.SNES().create(comm)
    snes.setOptionsPrefix(prefix)
    with default_options(prefix, options):
        snes.setFromOptions()
    return snes


def assemble_system(a: fem.Form, L: fem.Form, bcs: list[fem.DirichletBC]) -> tuple[PETSc.Mat, PETSc.Vec]:
    """Matrix of ``a`` with identity Dirichlet rows/columns and the lifted load of ``L``
    (the Dirichlet values on their dofs), in DOLFINx's assembly order."""
    A = dolfinx.fem.petsc.assemble_matrix(a, bcs=bcs)
    A.assemble()
    b = dolfinx.fem.petsc.assemble_vector(L)
    dolfinx.fem.petsc.apply_lifting(b, [a], bcs=[bcs])
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    dolfinx.fem.petsc.set_bc(b, bcs)
    return A, b


def reassemble_matrix(A: PETSc.Mat, form: fem.Form, bcs: list[fem.DirichletBC] | None = None) -> PETSc.Mat:
    """Assemble the bilinear ``form`` into ``A`` in place and return ``A``.

    ``A`` comes from an earlier assembly of ``form`` (its sparsity is reused);
    rows and columns of ``bcs`` get the identity as in ``assemble_matrix``.
    """
    A.zeroEntries()
    dolfinx.fem.petsc.assemble_matrix(A, form, bcs=bcs or [])
    A.assemble()
    return A


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


def nonzero_rows(M: PETSc.Mat) -> tuple[PETSc.IS, PETSc.Mat]:
    """The owned rows of ``M`` with a nonzero entry (global indices), and those rows of
    ``M`` with their nonzero entries only, as a new AIJ matrix (in M's column layout).

    Only those rows are read (PETSc finds them, :func:`nonzero_row_indices`): the changes
    this is made for are nonzero on few rows of a large pattern."""
    comm = M.getComm()
    rows = PETSc.IS().createGeneral(nonzero_row_indices(M), comm=comm)
    low, high = M.getOwnershipRangeColumn()
    columns = PETSc.IS().createStride(high - low, low, 1, comm=comm)  # all of M's columns
    sub = M.createSubMatrix(rows, columns)
    per_row, indices, values = _nonzero_entries(sub)
    compact = PETSc.Mat().createAIJ(size=((len(per_row), None), M.getSizes()[1]), comm=comm, csr=(
        np.concatenate([[0], np.cumsum(per_row)]).astype(PETSc.IntType), indices, values))
    compact.assemble()
    for obj in (columns, sub):
        obj.destroy()
    return rows, compact


def nonzero_row_indices(M: PETSc.Mat) -> np.ndarray:
    """Global indices of the owned rows of ``M`` that hold a nonzero value (explicit zeros
    do not count), ascending."""
    low, high = M.getOwnershipRange()
    zero = M.findZeroRows()
    nonzero = np.ones(high - low, dtype=bool)
    if zero:  # PETSc gives no index set at all (NULL) when no row of M is zero
        nonzero[zero.getIndices() - low] = False
    zero.destroy()
    return (np.flatnonzero(nonzero) + low).astype(PETSc.IntType)


def significant(M: PETSc.Mat, relative: float) -> PETSc.Mat:
    """``M`` without its entries of at most ``relative`` times the largest of their row (a new
    AIJ matrix of M's layout and block size): the cancelled terms of a difference of matrices,
    whose explicit entries every product and sweep with M would still visit."""
    per_row, indices, values = _nonzero_entries(M, relative)
    out = PETSc.Mat().createAIJ(size=M.getSizes(), bsize=M.getBlockSize(), comm=M.getComm(), csr=(
        np.concatenate([[0], np.cumsum(per_row)]).astype(PETSc.IntType), indices, values))
    out.assemble()
    return out


#: Rows read at a time by :func:`_nonzero_entries`: its work arrays are of that many rows, not of
#: the whole matrix (a 2-ring stencil of quadratic elements has about 1500 entries a row).
_ROWS_AT_A_TIME = 4096


def _nonzero_entries(M: PETSc.Mat, relative: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per owned row of ``M`` its number of entries larger than ``relative`` times the row's largest
    (0: its nonzero entries), and their columns and values."""
    indptr, indices, values = M.getValuesCSR()
    per_row, columns, kept = [], [], []
    for first in range(0, len(indptr) - 1, _ROWS_AT_A_TIME):
        bounds = indptr[first: first + _ROWS_AT_A_TIME + 1]
        lengths = np.diff(bounds)
        size = np.abs(values[bounds[0]: bounds[-1]])
        largest = np.zeros(len(lengths))
        if relative > 0.0 and size.size:
            largest[lengths > 0] = np.maximum.reduceat(size, (bounds[:-1] - bounds[0])[lengths > 0])
        keep = size > relative * np.repeat(largest, lengths)
        per_row.append(np.diff(np.concatenate([[0], np.cumsum(keep)])[bounds - bounds[0]]))
        columns.append(indices[bounds[0]: bounds[-1]][keep])
        kept.append(values[bounds[0]: bounds[-1]][keep])
    if not per_row:
        return np.zeros(0, dtype=np.int64), np.zeros(0, dtype=PETSc.IntType), np.zeros(0)
    return np.concatenate(per_row), np.concatenate(columns).astype(PETSc.IntType), np.concatenate(kept)
